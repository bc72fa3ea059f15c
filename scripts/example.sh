#!/usr/bin/env bash
# Set up (if needed), build in Release and run the two-link benchmark: two_link.h5 and
# two_link_tip.png (tip path, full view and zoom near the upper extreme) in the current folder.
set -euo pipefail
here=$(pwd)
cd "$(dirname "$0")/.."
root=$(pwd)
bash scripts/setup.sh
python=$(python3 -c 'import sys; print(sys.executable)')
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE="$python" > /dev/null
cmake --build build -j "$(nproc)"
cd "$here"
"$root/build/bin/flexmor" "$root/input/two_link.nml" -o two_link.h5
"$python" "$root/scripts/plot_tip_path.py" two_link.h5 -o two_link_tip.png
echo "example: wrote $here/two_link.h5 and $here/two_link_tip.png"
