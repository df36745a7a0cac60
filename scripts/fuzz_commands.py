#!/usr/bin/env python3
"""Mutated problem files of every form through every subcommand of the binary.

Each seed takes one bundled problem (matrix, geometry or hand form), makes one to
three edits (a number or value set to a hostile value: NaN, ±1e308, a subnormal, a
string, null, an array or object in a number's place; a number scaled by 10^±1 to
10^±9; a key deleted; an array's element removed or repeated, or the array emptied),
and runs one of `solve` (linear, exact, free internal forces, Clarabel's exact cones),
`compare`, `sweep`, `export-qp`, `bench`, `build` or `table` on it. It reports every run that
panics, hangs (60 s), exits with a code other than 0, 2, 3, 4 or 5 (`compare`'s
disagreement), fails without a message, or prints a non-finite number.

Usage: python3 scripts/fuzz_commands.py FROM COUNT   (after `cargo build --release`)
"""
import glob
import json
import os
import random
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "target", "release", "grasp-torque")
FILES = sorted(
    glob.glob(os.path.join(ROOT, "fixtures", "*.json"))
    + glob.glob(os.path.join(ROOT, "fixtures", "geometry", "*.json"))
    + glob.glob(os.path.join(ROOT, "fixtures", "hands", "*.json"))
)
HOSTILE = [float("nan"), 1e308, -1e308, 0, -0.0, 1e-320, 1e12, -1e12, 1e13, 1, -1, 2, 0.5,
           1e-9, 1e9, "x", None, True, [], {}, [1, 2], 3.5e-5]
COMMANDS = [
    ["compare"],
    ["sweep", "--sides", "4,8"],
    ["export-qp", "--format", "json"],
    ["bench", "--repeats", "3"],
    ["build"],
    ["table", "--format", "json"],
    ["solve", "--format", "json"],
    ["solve", "--cones", "exact", "--format", "json"],
    ["solve", "--internal-forces", "free", "--format", "json"],
    ["solve", "--backend", "clarabel", "--cones", "exact", "--format", "json"],
]
# A non-finite number as this project never prints one: NaN, inf, -inf as words.
NON_FINITE = re.compile(r"NaN|(?<![A-Za-z_])-?inf(?![A-Za-z_])")


def leaves(v, path=()):
    if isinstance(v, dict):
        for k, x in v.items():
            yield from leaves(x, path + (k,))
    elif isinstance(v, list):
        for i, x in enumerate(v):
            yield from leaves(x, path + (i,))
    else:
        yield path


def containers(v, path=()):
    if isinstance(v, (dict, list)):
        yield path, v
        for k, x in (v.items() if isinstance(v, dict) else enumerate(v)):
            yield from containers(x, path + (k,))


def reshape(problem, rnd):
    """A key deleted, or an array's element removed or repeated, or the array emptied."""
    path, c = rnd.choice([pc for pc in containers(problem) if pc[1]])
    name = ".".join(map(str, path)) or "(top level)"
    if isinstance(c, dict):
        k = rnd.choice(sorted(c))
        del c[k]
        return f"deleted {name}.{k}"
    i = rnd.randrange(len(c))
    op = rnd.choice(["remove", "repeat", "empty"])
    if op == "remove":
        del c[i]
    elif op == "repeat":
        c.insert(i, json.loads(json.dumps(c[i])))
    else:
        c.clear()
    return f"{op} {name}[{i}]"


def mutate(problem, rnd):
    paths = [p for p in leaves(problem) if "description" not in p and "name" not in p]
    done = []
    for _ in range(rnd.choice([1, 1, 2, 3])):
        if rnd.random() < 0.25:
            done.append(reshape(problem, rnd))
            paths = [p for p in leaves(problem) if "description" not in p and "name" not in p]
            continue
        if not paths:
            break
        path = rnd.choice(paths)
        parent = problem
        for k in path[:-1]:
            parent = parent[k]
        old = parent[path[-1]]
        if isinstance(old, (int, float)) and not isinstance(old, bool) and rnd.random() < 0.6:
            new = old * 10 ** rnd.choice([-9, -6, -3, -1, 1, 3, 6, 9]) * rnd.choice([1, -1])
        else:
            new = rnd.choice(HOSTILE)
        parent[path[-1]] = new
        done.append(f"{'.'.join(map(str, path))}={new!r}")
    return done


def main():
    start, count = int(sys.argv[1]), int(sys.argv[2])
    bad, exits = 0, {}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(start, start + count):
            rnd = random.Random(seed)
            source = rnd.choice(FILES)
            problem = json.load(open(source))
            if "hand" in problem:
                model = os.path.join(os.path.dirname(source), problem["hand"]["model"])
                problem["hand"]["model"] = os.path.abspath(model)
            edits = mutate(problem, rnd)
            path = os.path.join(tmp, "problem.json")
            with open(path, "w") as f:
                json.dump(problem, f)
            command = rnd.choice(COMMANDS)
            try:
                r = subprocess.run([BIN, command[0], path, *command[1:]],
                                   capture_output=True, text=True, timeout=60)
                code, out, err = r.returncode, r.stdout, r.stderr
            except subprocess.TimeoutExpired:
                code, out, err = "timeout", "", ""
            exits[code] = exits.get(code, 0) + 1
            wrong = (code not in (0, 2, 3, 4, 5) or "panicked" in err
                     or (code == 2 and not err.strip()) or bool(NON_FINITE.search(out)))
            if wrong:
                bad += 1
                print(f"seed {seed}: {os.path.basename(source)} ({edits}) {' '.join(command)}: "
                      f"exit {code}: {err[:300]}")
    print(f"seeds {start}..{start + count}: {bad} bad runs; exit codes {exits}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
