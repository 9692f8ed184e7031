#!/usr/bin/env python3
"""The labels file of the GelSight Mini slip set (amitparag/Incipient-Slip-Detection), for
`pvt3 import DIR --labels FILE.csv`: one touch a grasp, its first camera's video
(`camera_0.avi`), of class `slip` where the grasp's folder holds a `slip.txt` (the set marks a
slip so; the file is empty) and `wiggle` where it does not, with the object and the set's own
split as conditions (`--hold-out object=…`).

    python3 bench/slip_labels.py DIR > slip-labels.csv

DIR is the set's `docs/franka-servo/datasets` folder (holding `base_data_for_training` and
`base_data_for_validation`, then `<object>/exp_num_N/`).
"""
import sys
from pathlib import Path


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    root = Path(sys.argv[1])
    grasps = sorted(p.parent for p in root.glob("base_data_for_*/*/exp_num_*/camera_0.avi"))
    if not grasps:
        sys.exit(f"{root}: no base_data_for_*/<object>/exp_num_N/camera_0.avi")
    print("path,class,object,split")
    for grasp in grasps:
        split, obj = grasp.parts[-3].removeprefix("base_data_for_"), grasp.parts[-2]
        label = "slip" if (grasp / "slip.txt").exists() else "wiggle"
        print(f"{(grasp / 'camera_0.avi').relative_to(root).as_posix()},{label},{obj},{split}")


if __name__ == "__main__":
    main()
