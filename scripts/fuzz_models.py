#!/usr/bin/env python3
"""Mutated robot files under the bundled hand problems, through `grasp-torque solve`,
`hand` and `table`.

Each seed copies one hand's model folder (its URDF or MJCF with the files it
includes) to a temporary folder, edits one of its XML files 1 to 8 times (an
attribute set to a hostile value such as NaN, inf, 1e400, '' or the wrong arity, or to
another element's value of the same attribute; an element removed or duplicated; an
attribute deleted), sometimes adds gravity, and solves the hand problem on it with
linear and exact cones, lists the model (`hand`) and tabulates it (`table`). It
reports every run that panics, hangs (30 s), exits with a code other than 0, 2, 3 or
4, fails without a message, or prints a non-finite number.

Usage: python3 scripts/fuzz_models.py FROM COUNT   (after `cargo build --release`)
"""
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "target", "release", "grasp-torque")
HANDS = [os.path.join(ROOT, "fixtures", "hands", f) for f in sorted(os.listdir(os.path.join(ROOT, "fixtures", "hands")))]
HOSTILE = ["nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e400", "", " ", "abc", "0", "-0", "1e-320",
           "0 0 0", "1 2", "1 2 3 4 5", "nan 0 0", "0 0 1e308", "1e12 1e12 1e12", "-1", "2", "1e13",
           "0x10", "1,2,3", "true", "false", "auto", "999999999999999999999", "3.4.5", "+1", ".5"]


def mutate(tree, rnd):
    els = list(tree.getroot().iter())
    done = []
    for _ in range(rnd.choice([1, 2, 3, 5, 8])):
        e = rnd.choice(els)
        op = rnd.random()
        kids = list(e)
        if op < 0.3 and e.attrib:
            k = rnd.choice(list(e.attrib))
            e.attrib[k] = rnd.choice([x.attrib[k] for x in els if k in x.attrib])
            done.append(f"{e.tag}.{k}:={e.attrib[k]!r}")
        elif op < 0.7 and e.attrib:
            k = rnd.choice(list(e.attrib))
            e.attrib[k] = rnd.choice(HOSTILE) if rnd.random() < 0.8 else e.attrib[k] * 2
            done.append(f"{e.tag}.{k}={e.attrib[k]!r}")
        elif op < 0.8 and kids:
            c = rnd.choice(kids)
            e.remove(c)
            done.append(f"removed <{c.tag}> from <{e.tag}>")
        elif op < 0.9 and kids:
            c = rnd.choice(kids)
            e.append(c)
            done.append(f"duplicated <{c.tag}> in <{e.tag}>")
        elif e.attrib:
            k = rnd.choice(list(e.attrib))
            del e.attrib[k]
            done.append(f"deleted {e.tag}.{k}")
    return done


def non_finite(v):
    if isinstance(v, float):
        return v != v or v in (float("inf"), float("-inf"))
    if isinstance(v, list):
        return any(non_finite(x) for x in v)
    if isinstance(v, dict):
        return any(non_finite(x) for x in v.values())
    return False


def main():
    start, count = int(sys.argv[1]), int(sys.argv[2])
    bad = 0
    exits = {}
    for seed in range(start, start + count):
        rnd = random.Random(seed)
        hand = rnd.choice(HANDS)
        problem = json.load(open(hand))
        model = os.path.normpath(os.path.join(os.path.dirname(hand), problem["hand"]["model"]))
        with tempfile.TemporaryDirectory() as tmp:
            folder = os.path.join(tmp, "model")
            shutil.copytree(os.path.dirname(model), folder)
            copy = os.path.join(folder, os.path.basename(model))
            xmls = [os.path.join(folder, f) for f in os.listdir(folder) if f.endswith((".xml", ".urdf"))]
            target = copy if rnd.random() < 0.6 else rnd.choice(xmls)
            tree = ET.parse(target)
            edits = mutate(tree, rnd)
            tree.write(target)
            problem["hand"]["model"] = copy
            if rnd.random() < 0.3:
                problem["hand"]["gravity"] = [0, 0, -9.81]
            path = os.path.join(tmp, "problem.json")
            json.dump(problem, open(path, "w"))
            runs = {
                "linear": ["solve", path, "--cones", "linear"],
                "exact": ["solve", path, "--cones", "exact"],
                "hand": ["hand", copy],
                "table": ["table", path],
            }
            for cones, args in runs.items():
                try:
                    r = subprocess.run([BIN, *args, "--format", "json"],
                                       capture_output=True, text=True, timeout=30)
                    code, out, err = r.returncode, r.stdout, r.stderr
                except subprocess.TimeoutExpired:
                    code, out, err = "timeout", "", ""
                exits[code] = exits.get(code, 0) + 1
                wrong = code not in (0, 2, 3, 4) or "panicked" in err or (code == 2 and not err.strip())
                if code in (0, 3, 4):
                    try:
                        wrong |= non_finite(json.loads(out))
                    except ValueError:
                        wrong = True
                if wrong:
                    bad += 1
                    rel = os.path.relpath(target, folder)
                    print(f"seed {seed}: {os.path.basename(hand)} ({rel}: {edits}) {cones}: exit {code}: {err[:300]}")
    print(f"seeds {start}..{start + count}: {bad} bad runs; exit codes {exits}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
