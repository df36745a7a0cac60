#!/usr/bin/env bash
# The model build for a new grasp (`build_us` of `grasp-torque bench`: GraspSolver::new,
# the model, the inscribed view at N = 8 and the native backend), two builds of the CLI
# side by side on every fixture (scripts/bench_pair.sh).
# Usage: bash scripts/bench_build.sh BEFORE_BIN AFTER_BIN [REPEATS] [ROUNDS]
# (a BIN is a `grasp-torque` binary, for example an older commit's built in a worktree).
set -euo pipefail
cd "$(dirname "$0")/.."
exec bash scripts/bench_pair.sh "$1" "$2" build_us "${3:-2000}" "${4:-5}" \
  fixtures/*.json fixtures/hands/*.json -- --sides 8
