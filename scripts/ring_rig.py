#!/usr/bin/env python3
"""Writes a config.yaml of N copies of the published rig's first camera on a ring of 0.6 m,
facing outwards at equal angles (the rig of the README's timing by camera count):

    python3 scripts/ring_rig.py 6 > ring6.yaml
    omnimvs synth --kind things --rig ring6.yaml --frames 1..3 --seed 9300 --out ring6
"""
import math
import pathlib
import sys

PRESET = pathlib.Path(__file__).resolve().parent.parent / "crates/omnimvs-synth/src/sunny_cameras.yaml"


def main():
    count = int(sys.argv[1])
    if not 2 <= count <= 8:
        sys.exit("ring_rig.py: expected a number of cameras from 2 to 8")
    first = PRESET.read_text().split("cameras:\n")[1].split("  - cam_id: 2")[0]
    lines = ["config:\n  omnimvs_sweep_min_depth: 1.65\n\ncameras:\n"]
    for i in range(count):
        yaw = 2 * math.pi * i / count
        pose = f"pose: [0.0, {yaw!r}, 0.0, {0.6 * math.sin(yaw)!r}, 0.0, {0.6 * math.cos(yaw)!r}]"
        block = (
            first.replace("cam_id: 1", f"cam_id: {i + 1}")
            .replace('img_dir: "cam1"', f'img_dir: "cam{i + 1}"')
            .replace("pose: [0.000000, 0.000000, 0.000000, 0.000000, 0.000000, 0.600000]", pose)
        )
        lines.append(block)
    sys.stdout.write("".join(lines))


if __name__ == "__main__":
    main()
