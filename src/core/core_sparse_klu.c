/* A sparse LU factorisation (SuiteSparse KLU) behind an opaque handle for Fortran
 * (module core_sparse). The handle keeps KLU's settings, the symbolic analysis of one pattern
 * (compressed columns, 0-based) and the numeric factors of the latest values: one per matrix
 * owner, no global state, so that many models live in one process. */
#include <stdlib.h>
#include <string.h>
#include <klu.h>

typedef struct {
    klu_common common;
    klu_symbolic *symbolic;
    klu_numeric *numeric;
    int n;
    int *ap, *ai;
    /* rcond of the last full factorisation: a refactorisation that keeps the pivot order
     * but whose rcond falls far below it is redone with fresh pivoting. */
    double rcond_full;
} flexmor_klu_t;

void flexmor_klu_free(void *handle)
{
    flexmor_klu_t *h = handle;
    if (!h) return;
    if (h->numeric) klu_free_numeric(&h->numeric, &h->common);
    if (h->symbolic) klu_free_symbolic(&h->symbolic, &h->common);
    free(h->ap);
    free(h->ai);
    free(h);
}

/* Analyse the pattern (ap: n+1 column starts, ai: row indices, both 0-based); NULL when out
 * of memory or when KLU refuses the pattern. */
void *flexmor_klu_new(int n, const int *ap, const int *ai)
{
    flexmor_klu_t *h = calloc(1, sizeof *h);
    if (!h) return NULL;
    klu_defaults(&h->common);
    h->n = n;
    h->ap = malloc((size_t)(n + 1) * sizeof(int));
    h->ai = malloc((size_t)(ap[n] > 0 ? ap[n] : 1) * sizeof(int));
    if (!h->ap || !h->ai) { flexmor_klu_free(h); return NULL; }
    memcpy(h->ap, ap, (size_t)(n + 1) * sizeof(int));
    memcpy(h->ai, ai, (size_t)ap[n] * sizeof(int));
    h->symbolic = klu_analyze(n, h->ap, h->ai, &h->common);
    if (!h->symbolic) { flexmor_klu_free(h); return NULL; }
    return h;
}

/* Factorise the values ax (in the pattern's order). Returns 0 and the reciprocal pivot ratio
 * min|u_ii|/max|u_ii| in *rcond, or 1 when the matrix is singular. */
int flexmor_klu_factor(void *handle, const double *ax, double *rcond)
{
    flexmor_klu_t *h = handle;
    if (h->numeric) {
        /* The refactorisation's rcond (the cheap min/max |u_ii|, O(n)) is computed once: it
         * both decides whether to keep the pivot order and is the result. */
        if (!klu_refactor(h->ap, h->ai, (double *)ax, h->symbolic, h->numeric, &h->common)
            || !klu_rcond(h->symbolic, h->numeric, &h->common)
            || h->common.rcond < 1.0e-3 * h->rcond_full) {
            klu_free_numeric(&h->numeric, &h->common);
        }
    }
    if (!h->numeric) {
        h->numeric = klu_factor(h->ap, h->ai, (double *)ax, h->symbolic, &h->common);
        if (!h->numeric) return 1;
        if (!klu_rcond(h->symbolic, h->numeric, &h->common)) return 1;
        h->rcond_full = h->common.rcond;
    }
    *rcond = h->common.rcond;
    return h->common.status == KLU_SINGULAR || !(h->common.rcond > 0.0);
}

/* Solve A x = b (transposed != 0: A^T x = b) in place for nrhs columns of length n. */
int flexmor_klu_solve(void *handle, int nrhs, double *b, int transposed)
{
    flexmor_klu_t *h = handle;
    if (!h->numeric) return 1;
    if (transposed)
        return !klu_tsolve(h->symbolic, h->numeric, h->n, nrhs, b, &h->common);
    return !klu_solve(h->symbolic, h->numeric, h->n, nrhs, b, &h->common);
}
