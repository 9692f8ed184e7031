"""What a pressing force and the sliding direction do to FabricSlide's capacitive readings
(docs/robustness.md).

Force: for every force, the mean reading of the 16 capacitive channels over all touches of it
(their level) and the mean over touches of each channel's standard deviation within the touch
(how much it varies as the finger slides), each also divided by the force. Both grow about in
proportion to the force, which is what `pvt3 import --per-force` and `pvt3 cv --aug-scale` act on.

Direction: for every fabric touched both ways, each channel's level at positive speeds minus its
level at negative ones; beside it, each channel's spread within a touch and the standard
deviation of its level across the seven fabrics (what tells them apart).

    python3 bench/fabric_levels.py FABRICSLIDE      # a checkout of wngfra/FabricSlide
"""
import csv
import re
import statistics
import sys
from collections import defaultdict
from pathlib import Path

NAME = re.compile(r"(?P<fabric>\w+?)_F(?P<force>\d+)_V(?P<speed>-?\d+)mmps_\d+\.csv")
CHANNELS = [f"channel{k}" for k in range(1, 17)]


def touches(folder):
    """(fabric, force, speed, each channel's mean, each channel's standard deviation) per touch."""
    for path in sorted(folder.glob("*.csv")):
        m = NAME.fullmatch(path.name)
        if not m:
            continue
        with path.open() as f:
            rows = list(csv.DictReader(f, skipinitialspace=True))
        channels = [[float(r[c]) for r in rows] for c in CHANNELS]
        yield m["fabric"], int(m["force"]), int(m["speed"]), [statistics.mean(c) for c in channels], [statistics.pstdev(c) for c in channels]


def force_table(all_touches):
    levels, spreads = defaultdict(list), defaultdict(list)
    for _, force, _, means, stds in all_touches:
        levels[force].append(statistics.mean(means))
        spreads[force].append(statistics.mean(stds))
    print("| force | touches | level | level / force | spread | spread / force |")
    print("|---:|---:|---:|---:|---:|---:|")
    for force in sorted(levels):
        level, spread = statistics.mean(levels[force]), statistics.mean(spreads[force])
        print(f"| {force} | {len(levels[force])} | {level:.1f} | {level / force:.3f} | {spread:.2f} | {spread / force:.4f} |")


def column_means(rows):
    return [statistics.mean(column) for column in zip(*rows)]


def direction_table(all_touches):
    ways = defaultdict(lambda: ([], []))  # fabric -> (negative speeds' means, positive speeds')
    for fabric, _, speed, means, _ in all_touches:
        ways[fabric][speed > 0].append(means)
    fabric_levels = [column_means(back + forward) for back, forward in ways.values()]
    print("| channel | " + " | ".join(CHANNELS) + " |")
    print("|---|" + "---:|" * len(CHANNELS))
    for fabric, (back, forward) in sorted(ways.items()):
        if back and forward:
            shift = [f - b for f, b in zip(column_means(forward), column_means(back))]
            print(f"| {fabric}: forward − back | " + " | ".join(f"{v:+.1f}" for v in shift) + " |")
    print("| spread within a touch | " + " | ".join(f"{v:.1f}" for v in column_means([t[4] for t in all_touches])) + " |")
    print("| std of the level across fabrics | " + " | ".join(f"{statistics.pstdev(c):.1f}" for c in zip(*fabric_levels)) + " |")


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "FabricSlide") / "data" / "fabric"
    all_touches = list(touches(folder))
    if not all_touches:
        sys.exit(f"{folder}: no FabricSlide touches")
    force_table(all_touches)
    print()
    direction_table(all_touches)


if __name__ == "__main__":
    main()
