/* Small dense matrices (tens to hundreds of rows) are all flexmor gives BLAS: a threaded
 * OpenBLAS only burns system time on them, and an MPI sweep already uses every core. The
 * symbols are weak so that the reference BLAS (Debian's alternatives) links as well.
 *
 * OpenBLAS starts its thread pool when it is loaded (sized by OPENBLAS_NUM_THREADS, else the
 * core count), and an idle worker spins on sched_yield for about 0.1 s before it sleeps:
 * setting one thread does not stop that. So the pool is shut down as well (OpenBLAS's own
 * fork handler does the same; a later threaded call would start it again). Measured on 2
 * cores: 0.1 s of processor time less per run, a third of the two-link's expanded reduced
 * run at 64 elements per link. */
extern void openblas_set_num_threads(int) __attribute__((weak));
extern int blas_thread_shutdown_(void) __attribute__((weak));

void flexmor_single_thread_blas(void)
{
    if (openblas_set_num_threads) openblas_set_num_threads(1);
    if (blas_thread_shutdown_) blas_thread_shutdown_();
}
