"""Writes each reference case's problem (tests/data/reference-cases.json) to
OUTDIR/NAME.json with the reference's convention for the passive internal forces
("internal_forces": "euclidean"), as problem files for `grasp-torque` and the
instruction and timing scripts. Usage: python3 scripts/reference_problems.py OUTDIR"""
import json
import pathlib
import sys

root = pathlib.Path(__file__).resolve().parent.parent
out = pathlib.Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)
cases = json.loads((root / "tests" / "data" / "reference-cases.json").read_text())["cases"]
for case in cases:
    problem = dict(case.get("problem") or case["geometry"])
    problem["internal_forces"] = "euclidean"
    (out / f"{case['name']}.json").write_text(json.dumps(problem))
print(f"{len(cases)} problems in {out}")
