#!/usr/bin/env bash
# Set up (if needed), build in Release and run the two-link benchmark as the full model and as
# reduced models with 1 and 2 modes (the seed paper's Fig. 2): two_link.h5, two_link_1mode.h5,
# two_link_2modes.h5 and seed_fig2.png (tip paths, full view and detail near the upper extreme)
# in the current folder, and a table of tip errors, solve times and steps on the terminal; then
# two_link.gif, the full model's motion (flexmor-animate; flexmor-vtk writes it for ParaView).
# The Python side is the flexmor package, which scripts/setup.sh installs.
set -euo pipefail
here=$(pwd)
cd "$(dirname "$0")/.."
root=$(pwd)
bash scripts/setup.sh
python=$(python3 -c 'import sys; print(sys.executable)')
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE="$python" > /dev/null
# Only the two programs it runs, not the tests (scripts/test.sh builds those).
cmake --build build -j "$(nproc)" --target flexmor flexmor-sweep
cd "$here"
# The repository's own copy of the package, also when an older one is installed.
export PYTHONPATH="$root/python${PYTHONPATH:+:$PYTHONPATH}"
"$python" -m flexmor.seed_fig2 --bin "$root/build/bin/flexmor" --input-dir "$root/input" \
  --out-dir "$here"
"$python" -m flexmor.animate two_link.h5 -o two_link.gif --every 10
