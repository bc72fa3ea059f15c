#!/usr/bin/env bash
# Set up (if needed), build in Release and run the two-link benchmark as the full model and as
# reduced models with 1 and 2 modes (the seed paper's Fig. 2): two_link.h5, two_link_1mode.h5,
# two_link_2modes.h5 and seed_fig2.png (tip paths, full view and detail near the upper extreme)
# in the current folder, and a table of tip errors, solve times and steps on the terminal.
set -euo pipefail
here=$(pwd)
cd "$(dirname "$0")/.."
root=$(pwd)
bash scripts/setup.sh
python=$(python3 -c 'import sys; print(sys.executable)')
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE="$python" > /dev/null
cmake --build build -j "$(nproc)"
cd "$here"
"$python" "$root/scripts/seed_fig2.py" --bin "$root/build/bin/flexmor" --out-dir "$here"
