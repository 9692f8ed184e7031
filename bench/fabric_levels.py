"""What a pressing force does to FabricSlide's capacitive readings (docs/robustness.md): for every
force, the mean reading of the 16 capacitive channels over all touches of it (their level) and
the mean over touches of each channel's standard deviation within the touch (how much it varies
as the finger slides), each also divided by the force. Both grow about in proportion to the
force, which is what `pvt3 import --per-force` and `pvt3 cv --aug-scale` act on.

    python3 bench/fabric_levels.py FABRICSLIDE      # a checkout of wngfra/FabricSlide
"""
import csv
import re
import statistics
import sys
from collections import defaultdict
from pathlib import Path

NAME = re.compile(r"(?P<fabric>\w+?)_F(?P<force>\d+)_V(?P<speed>-?\d+)mmps_\d+\.csv")


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "FabricSlide") / "data" / "fabric"
    levels, spreads = defaultdict(list), defaultdict(list)
    for path in sorted(folder.glob("*.csv")):
        m = NAME.fullmatch(path.name)
        if not m:
            continue
        with path.open() as f:
            rows = list(csv.DictReader(f, skipinitialspace=True))
        channels = [[float(r[f"channel{k}"]) for r in rows] for k in range(1, 17)]
        force = int(m["force"])
        levels[force].append(statistics.mean(statistics.mean(c) for c in channels))
        spreads[force].append(statistics.mean(statistics.pstdev(c) for c in channels))
    if not levels:
        sys.exit(f"{folder}: no FabricSlide touches")
    print("| force | touches | level | level / force | spread | spread / force |")
    print("|---:|---:|---:|---:|---:|---:|")
    for force in sorted(levels):
        level, spread = statistics.mean(levels[force]), statistics.mean(spreads[force])
        print(f"| {force} | {len(levels[force])} | {level:.1f} | {level / force:.3f} | {spread:.2f} | {spread / force:.4f} |")


if __name__ == "__main__":
    main()
