#!/usr/bin/env bash
# Whether two builds give the same answers: `solve --format json` with each binary on
# each FILE at N = 8, N = 16 and on the exact cones, the status, σ and τ compared as
# printed (bit for bit). Prints one line per difference and a count.
# Usage: bash scripts/compare_answers.sh OLD_BIN NEW_BIN FILE...
#   e.g. python3 scripts/reference_problems.py /tmp/refcases, then
#   bash scripts/compare_answers.sh /tmp/old/release/grasp-torque target/release/grasp-torque \
#     fixtures/*.json fixtures/*/*.json /tmp/refcases/*.json
set -uo pipefail
old=$1 new=$2
shift 2
answer() {
  "$1" solve "$2" $3 --format json 2>/dev/null |
    python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["status"], repr(d.get("objective")), d.get("torque"))' 2>/dev/null ||
    echo "no answer"
}
same=0 differ=0
for f in "$@"; do
  for flags in "--sides 8" "--sides 16" "--cones exact"; do
    a=$(answer "$old" "$f" "$flags")
    b=$(answer "$new" "$f" "$flags")
    if [ "$a" = "$b" ]; then
      same=$((same + 1))
    else
      differ=$((differ + 1))
      echo "differ: $f $flags"
      echo "  old: $a"
      echo "  new: $b"
    fi
  done
done
echo "$same identical, $differ differ"
