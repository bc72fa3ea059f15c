#!/usr/bin/env bash
# Set up (if needed), build in Debug (-fcheck=all, FPE traps) and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
python=$(python3 -c 'import sys; print(sys.executable)')
cmake -S . -B build-debug -DCMAKE_BUILD_TYPE=Debug -DPython3_EXECUTABLE="$python" > /dev/null
cmake --build build-debug -j "$(nproc)"
cd build-debug
ctest --output-on-failure -j "$(nproc)"
