/* glibc serves allocations above its mmap threshold (128 KiB at start) with mmap and unmaps
 * them on free; only freeing such a chunk raises the threshold, up to 32 MiB. A reduced run
 * allocates series and projections of a few hundred KiB again and again (expansions,
 * indicators): until some larger array has been freed, each one costs fresh page faults.
 * On the two-link with 64 beams per link and the Krylov basis (no large dense matrix freed
 * early) that was 19,000 more minor faults and 40 % more processor time than with a dense
 * basis. The executables set the threshold where glibc's adaptation ends, and the trim
 * threshold to twice that as the adaptation does. */
#include <malloc.h>

void flexmor_steady_heap(void)
{
#ifdef M_MMAP_THRESHOLD
    mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
    mallopt(M_TRIM_THRESHOLD, 64 * 1024 * 1024);
#endif
}
