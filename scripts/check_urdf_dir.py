#!/usr/bin/env python3
"""Every URDF under a directory against Pinocchio, once: loads each with grasp-torque
and Pinocchio, samples configurations and contacts on its leaf links as
`oracle_urdf.py` does, and compares grasp-torque's Jᵀ and G (from `grasp-torque build`)
with Pinocchio's. For hand collections that cannot be redistributed as fixtures
(docs/hands.md, "How the Jacobians are checked"); nothing is written to the repository.

Run from the repository root, after `cargo build --release` (pin 4.1.0 and numpy from
PyPI; see oracle_urdf.py), with a dex-urdf checkout at commit 93505db3c0b2, say:

    /tmp/oracle/bin/python scripts/check_urdf_dir.py DEX_URDF/robots/hands [CASES]

URDFs whose name ends in `_glb` (the same kinematics with other meshes) are skipped.
"""

import glob
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    top = os.path.abspath(sys.argv[1])
    cases = int(sys.argv[2]) if len(sys.argv) > 2 else 30
    spec = importlib.util.spec_from_file_location(
        "oracle", os.path.join(ROOT, "scripts", "oracle_urdf.py"))
    oracle = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(oracle)
    files = sorted(f for f in glob.glob(os.path.join(top, "**", "*.urdf"), recursive=True)
                   if not f.endswith("_glb.urdf"))
    out = tempfile.mkdtemp()
    oracle.OUT, oracle.CASES, oracle.RANDOM = out, cases, out
    hands = []
    for i, path in enumerate(files):
        root = ET.parse(path).getroot()
        parents = {j.find("parent").get("link") for j in root.iter("joint")}
        leaves = [j.find("child").get("link") for j in root.iter("joint")
                  if j.find("child").get("link") not in parents]
        name = os.path.relpath(path, top).replace(os.sep, "__")[:-5]
        hands.append((name, path, False, leaves[:6], 100 + i))
    oracle.HANDS = hands
    oracle.main()
    cli = os.path.join(ROOT, "target", "release", "grasp-torque")
    failed = 0
    for name, path, *_ in hands:
        worst = 0.0
        for case in json.load(open(os.path.join(out, f"{name}.json")))["cases"]:
            p = case["problem"]
            p["hand"]["model"] = path
            with open(os.path.join(out, "p.json"), "w") as f:
                json.dump(p, f)
            r = subprocess.run([cli, "build", os.path.join(out, "p.json")],
                               capture_output=True, text=True)
            if r.returncode != 0:
                print(f"{name}: build failed: {r.stderr.strip()}")
                failed += 1
                break
            m = json.loads(r.stdout)
            expect = case["jacobian_transpose"]
            scale = max(abs(v) for row in expect.values() for v in row) or 1.0
            for j, row in zip(m["joint_names"], m["jacobian_transpose"]):
                worst = max(worst, np.abs(np.array(row) - expect[j]).max() / scale)
            G, G0 = np.array(m["grasp_matrix"]), np.array(case["grasp_matrix"])
            worst = max(worst, np.abs(G - G0).max() / max(1.0, np.abs(G0).max()))
        print(f"{name}: worst relative error {worst:.1e}")
        failed += worst > 1e-10
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
