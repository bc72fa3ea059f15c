#!/usr/bin/env bash
# Example Slurm job: a flexmor parameter sweep (docs/sweep.md) on N nodes x T tasks per node.
#
#   sbatch scripts/slurm_sweep.sh                 # from the repository root (build/ done)
#   sbatch --nodes=4 --ntasks-per-node=32 scripts/slurm_sweep.sh   # override the size
#
# Size: the job runs nodes x ntasks-per-node MPI ranks (set both below, or on the sbatch
# command line, which wins over the #SBATCH lines). Each rank is one single-threaded process
# (flexmor-sweep pins BLAS to one thread), so use one task per core: e.g. 2 nodes with 64
# cores each -> --nodes=2 --ntasks-per-node=64 (128 ranks). Rank 0 hands out the cases one at a
# time and writes the result file; ranks 1..N-1 run cases, so more ranks than cases gain
# nothing. Cases are handed out dynamically, so uneven case costs (full vs reduced models)
# balance by themselves.
#
# Resuming: rank 0 writes and flushes every finished case. If the job is killed (time limit,
# node failure, scancel), submit the same job again with the same -o file: cases already in
# the file are skipped and only the rest are run. Use a fresh file name for a fresh sweep.
#
# Afterwards (on a login node):
#   flexmor-sweep-summary sweep.h5            # table, failures, wall-time spread
#   flexmor-sweep-summary sweep.h5 --failed   # only the failed cases
#   flexmor-sweep-plot sweep.h5 --metric max_tip_deflection --x PARAM -o plot.png
#   flexmor-sweep-tradeoff sweep.h5 --fidelity reduction.n_modes -o tradeoff.png
#
#SBATCH --job-name=flexmor-sweep
#SBATCH --nodes=2
#SBATCH --ntasks-per-node=32
#SBATCH --cpus-per-task=1
#SBATCH --time=02:00:00
#SBATCH --output=flexmor-sweep-%j.out
#SBATCH --error=flexmor-sweep-%j.out
##SBATCH --partition=compute        # site specific: uncomment and set
##SBATCH --account=my_project       # site specific: uncomment and set

set -euo pipefail

# Site modules: load the same compiler, MPI and HDF5 that built flexmor (names vary by site).
# module purge
# module load gcc/12 openmpi/4.1 hdf5/1.10-openmpi sundials/6.4

# One thread per rank (flexmor-sweep also sets this for BLAS itself).
export OMP_NUM_THREADS=1
export OPENBLAS_NUM_THREADS=1

# Run from the folder sbatch was called in (the repository root for the paths below). The
# result file must be on a file system that the node running rank 0 can write.
cd "${SLURM_SUBMIT_DIR:-.}"

echo "flexmor-sweep: ${SLURM_JOB_NUM_NODES:-?} node(s), ${SLURM_NTASKS:-?} rank(s)," \
     "job ${SLURM_JOB_ID:-?}"
srun build/bin/flexmor-sweep input/sweep_two_link.nml -o sweep.h5
