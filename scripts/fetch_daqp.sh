#!/usr/bin/env bash
# DAQP's C sources for the peer benchmark (`cargo bench -p grasp-daqp`), from its PyPI
# source distribution (MIT), into target/daqp/csrc. Needs python3 (pip, or venv to get it).
# Usage: bash scripts/fetch_daqp.sh [VERSION]
set -euo pipefail
cd "$(dirname "$0")/.."
version=${1:-0.11.0}
dest=target/daqp
rm -rf "$dest" && mkdir -p "$dest"
if python3 -m pip --version >/dev/null 2>&1; then
  pip=(python3 -m pip)
else
  python3 -m venv "$dest/venv"
  pip=("$dest/venv/bin/pip")
fi
"${pip[@]}" download "daqp==$version" --no-binary :all: --no-deps -d "$dest" -q
tar xzf "$dest/daqp-$version.tar.gz" -C "$dest"
mv "$dest/daqp-$version/csrc" "$dest/csrc"
cp "$dest/daqp-$version/LICENSE" "$dest/csrc/LICENSE"
echo "DAQP $version sources in $dest/csrc; now: cargo bench -p grasp-daqp"
