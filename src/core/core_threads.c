/* Small dense matrices (tens to hundreds of rows) are all flexmor gives BLAS: a threaded
 * OpenBLAS only burns system time on them, and an MPI sweep already uses every core. The
 * symbol is weak so that the reference BLAS (Debian's alternatives) links as well. */
extern void openblas_set_num_threads(int) __attribute__((weak));

void flexmor_single_thread_blas(void)
{
    if (openblas_set_num_threads) openblas_set_num_threads(1);
}
