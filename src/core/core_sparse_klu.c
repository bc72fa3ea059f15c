/* A sparse LU factorisation (SuiteSparse KLU) behind an opaque handle for Fortran
 * (module core_sparse). The handle keeps KLU's settings, the symbolic analysis of one pattern
 * (compressed columns, 0-based) and the numeric factors of the latest values: one per matrix
 * owner, no global state, so that many models live in one process.
 *
 * Row scaling is done here rather than by KLU, with KLU's own rule (its default scale = 2:
 * each row divided by its largest magnitude, 1 for an empty row) and the same divisions, so
 * that KLU sees the same scaled values and its pivots and factors are bitwise those of its
 * own scaling (the solutions to the last bit: they multiply by the reciprocals). KLU's scaling pass checks every row index on every
 * refactorisation (the pattern here is fixed at creation); the plain pass here, with the
 * divisions KLU's refactorisation no longer makes, is 2 % fewer instructions per step
 * (two-link, 64 elements per link, callgrind). */
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <klu.h>

typedef struct {
    klu_common common;
    klu_symbolic *symbolic;
    klu_numeric *numeric;
    int n;
    int *ap, *ai;
    double *rs;     /* row scale factors of the last factorisation (n) */
    double *rs_inv; /* their reciprocals: a solve multiplies (a division per entry costs
                       several products' time, and solves outnumber factorisations) */
    double *ax_s;   /* the scaled values handed to KLU (nnz) */
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
    free(h->rs);
    free(h->rs_inv);
    free(h->ax_s);
    free(h);
}

/* Analyse the pattern (ap: n+1 column starts, ai: row indices, both 0-based); NULL when out
 * of memory or when KLU refuses the pattern. */
void *flexmor_klu_new(int n, const int *ap, const int *ai)
{
    flexmor_klu_t *h = calloc(1, sizeof *h);
    if (!h) return NULL;
    klu_defaults(&h->common);
    /* No scaling (and no input checks) inside KLU: scale_values does it (see above). */
    h->common.scale = -1;
    h->n = n;
    h->ap = malloc((size_t)(n + 1) * sizeof(int));
    h->ai = malloc((size_t)(ap[n] > 0 ? ap[n] : 1) * sizeof(int));
    h->rs = malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    h->rs_inv = malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    h->ax_s = malloc((size_t)(ap[n] > 0 ? ap[n] : 1) * sizeof(double));
    if (!h->ap || !h->ai || !h->rs || !h->rs_inv || !h->ax_s) { flexmor_klu_free(h); return NULL; }
    memcpy(h->ap, ap, (size_t)(n + 1) * sizeof(int));
    memcpy(h->ai, ai, (size_t)ap[n] * sizeof(int));
    h->symbolic = klu_analyze(n, h->ap, h->ai, &h->common);
    if (!h->symbolic) { flexmor_klu_free(h); return NULL; }
    return h;
}

/* KLU's scale = 2 rule: rs[i] = max_j |a_ij| (1 where the row is empty or zero), and
 * ax_s = a_ij / rs[i], as KLU divides during its factorisation. */
static void scale_values(flexmor_klu_t *h, const double *ax)
{
    const int n = h->n, nnz = h->ap[h->n];
    const int *restrict ai = h->ai;
    double *restrict rs = h->rs, *restrict rs_inv = h->rs_inv, *restrict ax_s = h->ax_s;
    int j, p;
    for (j = 0; j < n; j++) rs[j] = 0.0;
    for (p = 0; p < nnz; p++) {
        double a = fabs(ax[p]);
        if (a > rs[ai[p]]) rs[ai[p]] = a;
    }
    for (j = 0; j < n; j++) {
        if (rs[j] == 0.0) rs[j] = 1.0;
        rs_inv[j] = 1.0 / rs[j];
    }
    for (p = 0; p < nnz; p++) ax_s[p] = ax[p] / rs[ai[p]];
}

/* Factorise the values ax (in the pattern's order). Returns 0 and the reciprocal pivot ratio
 * min|u_ii|/max|u_ii| in *rcond, or 1 when the matrix is singular. */
int flexmor_klu_factor(void *handle, const double *ax, double *rcond)
{
    flexmor_klu_t *h = handle;
    scale_values(h, ax);
    if (h->numeric) {
        /* The refactorisation's rcond (the cheap min/max |u_ii|, O(n)) is computed once: it
         * both decides whether to keep the pivot order and is the result. */
        if (!klu_refactor(h->ap, h->ai, h->ax_s, h->symbolic, h->numeric, &h->common)
            || !klu_rcond(h->symbolic, h->numeric, &h->common)
            || h->common.rcond < 1.0e-3 * h->rcond_full) {
            klu_free_numeric(&h->numeric, &h->common);
        }
    }
    if (!h->numeric) {
        h->numeric = klu_factor(h->ap, h->ai, h->ax_s, h->symbolic, &h->common);
        if (!h->numeric) return 1;
        if (!klu_rcond(h->symbolic, h->numeric, &h->common)) return 1;
        h->rcond_full = h->common.rcond;
    }
    *rcond = h->common.rcond;
    return h->common.status == KLU_SINGULAR || !(h->common.rcond > 0.0);
}

/* Factorise afresh with full partial pivoting (KLU's tol = 1 instead of its 0.001, which
 * prefers the diagonal): for a matrix whose factors came out unusable. Later refactorisations
 * keep the pivot order found here while their rcond holds. */
int flexmor_klu_factor_pivoting(void *handle, const double *ax, double *rcond)
{
    flexmor_klu_t *h = handle;
    const double tol = h->common.tol;
    int info;
    if (h->numeric) klu_free_numeric(&h->numeric, &h->common);
    h->common.tol = 1.0;
    info = flexmor_klu_factor(handle, ax, rcond);
    h->common.tol = tol;
    return info;
}

/* Solve A x = b (transposed != 0: A^T x = b) in place for nrhs columns of length n. With
 * A = R A_s (R = diag(rs)): A x = b is A_s x = R^-1 b, and A^T x = b is x = R^-1 (A_s^-T b),
 * by the reciprocals (KLU divides: the solutions differ from its own in the last bit). */
int flexmor_klu_solve(void *handle, int nrhs, double *b, int transposed)
{
    flexmor_klu_t *h = handle;
    const int n = h->n;
    const double *restrict rs_inv = h->rs_inv;
    int i, c, ok;
    if (!h->numeric) return 1;
    if (transposed) {
        ok = klu_tsolve(h->symbolic, h->numeric, n, nrhs, b, &h->common);
        for (c = 0; c < nrhs; c++)
            for (i = 0; i < n; i++) b[(size_t)c * n + i] *= rs_inv[i];
        return !ok;
    }
    for (c = 0; c < nrhs; c++)
        for (i = 0; i < n; i++) b[(size_t)c * n + i] *= rs_inv[i];
    return !klu_solve(h->symbolic, h->numeric, n, nrhs, b, &h->common);
}

/* KLU's ordering of the analysed pattern: A(P, Q) is block upper triangular with diagonal
 * blocks r[k] .. r[k+1]-1 (0-based; p, q of size n, r of size n+1). Returns the number of
 * blocks and the size of the largest in *maxblock. */
int flexmor_klu_ordering(void *handle, int *p, int *q, int *r, int *maxblock)
{
    flexmor_klu_t *h = handle;
    const klu_symbolic *s = h->symbolic;
    memcpy(p, s->P, (size_t)h->n * sizeof(int));
    memcpy(q, s->Q, (size_t)h->n * sizeof(int));
    memcpy(r, s->R, (size_t)(s->nblocks + 1) * sizeof(int));
    *maxblock = s->maxblock;
    return s->nblocks;
}
