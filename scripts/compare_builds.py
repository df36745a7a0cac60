#!/usr/bin/env python3
"""Two grasp-torque binaries on every hand problem the repository has: the oracle cases
of fixtures/urdf/oracle, fixtures/mjcf/oracle and fixtures/mjcf/gravity (with their
gravity) and the bundled fixtures/hands files. Each is written as a hand-form file with
an absolute robot path and turned into the matrix form by `grasp-torque build`; the
outputs (G, Jᵀ, T, passive torques, every number printed to round-trip) must be equal
byte for byte. For a change that must not move any frame, such as the readers' own
3-D frames replacing nalgebra's.

    python3 scripts/compare_builds.py OLD_BINARY NEW_BINARY
"""

import glob
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def problems():
    out = []
    oracles = sorted(
        glob.glob(f"{ROOT}/fixtures/urdf/oracle/*.json")
        + glob.glob(f"{ROOT}/fixtures/mjcf/oracle/*.json")
        + glob.glob(f"{ROOT}/fixtures/mjcf/gravity/oracle.json")
    )
    for f in oracles:
        for case in json.load(open(f)).get("cases", []):
            p = case.get("problem")
            if not p or "hand" not in p:
                continue
            p = json.loads(json.dumps(p))
            p["hand"]["model"] = os.path.normpath(os.path.join(os.path.dirname(f), p["hand"]["model"]))
            if case.get("gravity") is not None:
                p["hand"]["gravity"] = case["gravity"]
            out.append(p)
    for f in sorted(glob.glob(f"{ROOT}/fixtures/hands/*.json")):
        p = json.load(open(f))
        p["hand"]["model"] = os.path.normpath(os.path.join(os.path.dirname(f), p["hand"]["model"]))
        out.append(p)
    return out


def main():
    old, new = sys.argv[1:3]
    same, differ = 0, []
    with tempfile.TemporaryDirectory() as tmp:
        for i, p in enumerate(problems()):
            path = os.path.join(tmp, f"p{i}.json")
            with open(path, "w") as f:
                json.dump(p, f)
            a, b = (subprocess.run([exe, "build", path], capture_output=True, text=True) for exe in (old, new))
            if (a.returncode, a.stdout, a.stderr) == (b.returncode, b.stdout, b.stderr):
                same += 1
            else:
                differ.append(p.get("name", f"problem {i}"))
    print(f"{same} identical, {len(differ)} differ{': ' + ', '.join(differ[:10]) if differ else ''}")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
