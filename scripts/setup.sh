#!/usr/bin/env bash
# Install what flexmor needs on Debian 12 (see docs of the toolchain): the Debian packages that
# are missing, numpy/h5py/matplotlib/meshio/scipy/control/pytest/wheel for the python3 on PATH
# if it cannot import them, and the flexmor Python package (python/flexmor, `pip install .` of
# the repository) when it is not installed or its version differs from the repository's VERSION.
# Safe to run again: it checks first and only installs what is missing (no apt-get update when
# nothing is missing). Runs as root, or through sudo when not root.
#
#   bash scripts/setup.sh            # install what is missing
#   bash scripts/setup.sh --check    # only report what is missing (exit 1 if anything is)
#
# The serial libhdf5-dev is deliberately not installed: its h5fc would be preferred by CMake's
# FindHDF5 over the Open MPI build (libhdf5-openmpi-dev) that flexmor uses.
set -euo pipefail

DEBIAN_PACKAGES=(
  gfortran libopenmpi-dev openmpi-bin libhdf5-openmpi-dev hdf5-tools
  libarpack2-dev libparpack2-dev libsundials-dev libsundials-fortran-dev libsuitesparse-dev
  liblapack-dev libopenblas-dev pkg-config cmake make
)
# wheel: lets tests/python/test_package.py build the package without network (setuptools < 70.1).
# scipy, control (python-control): flexmor.control's state-space systems and zeros.
PYTHON_PACKAGES=(numpy h5py matplotlib meshio scipy control pytest wheel)
PYTHON_IMPORTS="import numpy, h5py, matplotlib, meshio, scipy, control, pytest, wheel"

check_only=0
case "${1:-}" in
  --check) check_only=1 ;;
  "") ;;
  -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  *) echo "setup.sh: unknown option '$1' (use --check or nothing)" >&2; exit 2 ;;
esac

say() { echo "setup: $*"; }

# Run a command as root: directly when root, else through sudo if there is one.
as_root() {
  if [[ $(id -u) -eq 0 ]]; then
    "$@"
  elif command -v sudo > /dev/null 2>&1; then
    sudo "$@"
  else
    echo "setup: need root (or sudo) to run: $*" >&2
    exit 1
  fi
}

installed() {
  dpkg -s "$1" 2> /dev/null | grep -q '^Status: install ok installed'
}

apt_updated=0
apt_install() {
  if [[ $apt_updated -eq 0 ]]; then
    as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q > /dev/null
    apt_updated=1
  fi
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q "$@" > /dev/null
}

if ! command -v dpkg > /dev/null 2>&1; then
  echo "setup: dpkg not found: this script is for Debian 12" >&2
  exit 1
fi

missing_status=0

# --- Debian packages -------------------------------------------------------------------------
missing=()
for pkg in "${DEBIAN_PACKAGES[@]}"; do
  installed "$pkg" || missing+=("$pkg")
done
if [[ ${#missing[@]} -eq 0 ]]; then
  say "Debian packages: all ${#DEBIAN_PACKAGES[@]} present"
elif [[ $check_only -eq 1 ]]; then
  say "Debian packages missing: ${missing[*]}"
  missing_status=1
else
  say "Debian packages: installing ${missing[*]}"
  apt_install "${missing[@]}"
  say "Debian packages: installed ${#missing[@]}"
fi
if installed libhdf5-dev; then
  say "warning: the serial libhdf5-dev is installed; CMake must find the Open MPI HDF5" \
      "(HDF5_PREFER_PARALLEL is set; check that HDF5_IS_PARALLEL is TRUE)"
fi

# --- Python packages -------------------------------------------------------------------------
if ! command -v python3 > /dev/null 2>&1; then
  if [[ $check_only -eq 1 ]]; then
    say "python3 missing"
    exit 1
  fi
  say "python3: installing python3 python3-pip"
  apt_install python3 python3-pip
fi
python=$(command -v python3)
python_exe=$(python3 -c 'import sys; print(sys.executable)')
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_ROOT_USER_ACTION=ignore

# pip install as the user running the script (a pyenv interpreter belongs to that user); Debian's
# own python3 refuses with "externally-managed-environment" unless told otherwise.
pip_install() {
  local log
  if ! python3 -m pip --version > /dev/null 2>&1; then
    # A pyenv or self-built interpreter brings ensurepip; Debian's python3 needs python3-pip.
    if ! python3 -m ensurepip --upgrade > /dev/null 2>&1; then
      say "pip: installing python3-pip"
      apt_install python3-pip
    fi
  fi
  if ! log=$(python3 -m pip install --quiet "$@" 2>&1); then
    if grep -q 'externally-managed-environment' <<< "$log"; then
      say "pip: externally managed environment, retrying with --break-system-packages"
      python3 -m pip install --quiet --break-system-packages "$@"
    else
      echo "$log" >&2
      echo "setup: pip install $* failed for $python_exe" >&2
      exit 1
    fi
  fi
}

if python3 -c "$PYTHON_IMPORTS" > /dev/null 2>&1; then
  say "Python packages: ${PYTHON_PACKAGES[*]} importable by $python_exe"
elif [[ $check_only -eq 1 ]]; then
  say "Python packages: some of ${PYTHON_PACKAGES[*]} not importable by $python_exe"
  missing_status=1
else
  say "Python packages: pip install ${PYTHON_PACKAGES[*]} for $python_exe"
  pip_install "${PYTHON_PACKAGES[@]}"
  if ! python3 -c "$PYTHON_IMPORTS" > /dev/null 2>&1; then
    echo "setup: after pip install, '$python' still cannot run: $PYTHON_IMPORTS" >&2
    python3 -c "$PYTHON_IMPORTS" || true
    exit 1
  fi
  say "Python packages: installed"
fi

# --- the flexmor Python package ----------------------------------------------------------------
# The installed copy (not one on PYTHONPATH; imported outside the repository) must have the
# repository's version and the repository's modules: a module added or changed within a
# version (a new command) would otherwise be missing from a machine that installed it before.
root=$(cd "$(dirname "$0")/.." && pwd)
want=$(tr -d '[:space:]' < "$root/VERSION")
flexmor_version() {
  (cd / && env -u PYTHONPATH python3 -c 'import flexmor; print(flexmor.__version__)' 2> /dev/null) \
    || true
}
flexmor_modules_current() {
  (cd / && env -u PYTHONPATH python3 -c '
import filecmp, pathlib, sys, flexmor
src, inst = pathlib.Path(sys.argv[1]), pathlib.Path(flexmor.__file__).parent
names = sorted(p.name for p in src.glob("*.py"))
sys.exit(0 if filecmp.cmpfiles(src, inst, names, shallow=False)[0] == names else 1)
' "$root/python/flexmor" 2> /dev/null)
}
have=$(flexmor_version)
if [[ "$have" == "$want" ]] && ! flexmor_modules_current; then
  have="$want with other modules than the repository's"
fi
if [[ "$have" == "$want" ]]; then
  say "flexmor Python package: $want installed"
elif [[ $check_only -eq 1 ]]; then
  say "flexmor Python package: ${have:-not installed}, repository has $want"
  missing_status=1
else
  say "flexmor Python package: ${have:-not installed}, installing $want (pip install $root)"
  pip_install "$root"
  have=$(flexmor_version)
  if [[ "$have" != "$want" ]]; then
    echo "setup: after pip install, 'import flexmor' gives version '${have:-none}', not $want" >&2
    exit 1
  fi
  say "flexmor Python package: installed $want"
fi

if [[ $check_only -eq 1 ]]; then
  if [[ $missing_status -eq 0 ]]; then say "nothing missing"; fi
  exit "$missing_status"
fi
say "done (python: $python_exe; build with cmake -DPython3_EXECUTABLE=$python_exe)"
