/* Blocked MLP evaluation and native screening (seed 000: one million combinations x every
 * property net). Rows are processed in blocks of BLOCK so that each hidden unit is one
 * vectorisable loop over the block; tanh is evaluated by fast_tanh (below), accurate to a few
 * ulp, because libm's tanh does not vectorise and would dominate the cost. */
#include "mlp_internal.h"
#include "alloc.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#define BLOCK 128

/* a*b + c: one fused instruction where the target has FMA (twice as fast here, and the
 * polynomial is the cost), plain arithmetic elsewhere (a software fma would be slow). */
#ifdef __FMA__
#define MADD(a, b, c) fma((a), (b), (c))
#else
#define MADD(a, b, c) ((a) * (b) + (c))
#endif

/* tanh(x) = -expm1(-2|x|) / (2 + expm1(-2|x|)) with the sign of x. expm1(y), y in [-40, 0]:
 * y = k ln2 + r with |r| <= ln2/2; exp(r) - 1 = q(r) by its Taylor series to r^12 (truncation
 * < 2e-16 relative); expm1(y) = 2^k q + (2^k - 1), exact for k = 0 so small |x| keeps full
 * relative accuracy. 2^k is assembled from bits (k + 1023 in the exponent field). Beyond
 * |x| = 20, tanh is 1 to double precision. Plain arithmetic only, so the loop vectorises. */
static inline double fast_tanh(double x)
{
    const double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10;
    const double log2e = 1.44269504088896338700e+00, shifter = 6755399441055744.0; /* 1.5 x 2^52 */
    double a = fabs(x), y, kd, r, r2, r4, r8, b0, b1, b2, q, scale, t, em1;
    uint64_t bits;
    a = a < 20.0 ? a : 20.0;
    y = -2.0 * a;
    kd = MADD(y, log2e, shifter) - shifter; /* round to nearest integer */
    r = (y - kd * ln2_hi) - kd * ln2_lo;
    /* q = r + r^2 (1/2! + r/3! + ... + r^10/12!) by Estrin's scheme: a dependency chain of ~6
     * operations instead of Horner's 11, so the vector units stay busy */
    r2 = r * r;
    r4 = r2 * r2;
    r8 = r4 * r4;
    b0 = MADD(MADD(1.0 / 120.0, r, 1.0 / 24.0), r2, MADD(1.0 / 6.0, r, 0.5));
    b1 = MADD(MADD(1.0 / 362880.0, r, 1.0 / 40320.0), r2, MADD(1.0 / 5040.0, r, 1.0 / 720.0));
    b2 = MADD(1.0 / 479001600.0, r2, MADD(1.0 / 39916800.0, r, 1.0 / 3628800.0));
    q = MADD(b2, r8, MADD(b1, r4, b0));
    q = MADD(q, r2, r);
    t = kd + shifter;
    memcpy(&bits, &t, sizeof bits);
    bits = (bits + 1023u) << 52;
    memcpy(&scale, &bits, sizeof scale);
    em1 = MADD(scale, q, scale - 1.0);
    t = -em1 / (2.0 + em1);
    return x < 0 ? -t : t;
}

/* y[b] for nb <= BLOCK rows; xs is scratch of nin x BLOCK. */
static void eval_block(const dem_mlp *m, const double *x, int nb, double *xs, double *y)
{
    double z[BLOCK], acc[BLOCK];
    const double half = (m->out_hi - m->out_lo) / 2.0;
    int i, j, b;
    for (i = 0; i < m->nin; ++i) {
        const double lo = m->in_lo[i], s = 2.0 / (m->in_hi[i] - m->in_lo[i]);
        double *xi = xs + (size_t)i * BLOCK;
        for (b = 0; b < nb; ++b)
            xi[b] = (x[(size_t)b * (size_t)m->nin + (size_t)i] - lo) * s - 1.0;
    }
    for (b = 0; b < nb; ++b)
        acc[b] = m->b2;
    for (j = 0; j < m->nhid; ++j) {
        const double *wj = m->w1 + (size_t)j * (size_t)m->nin;
        const double b1 = m->b1[j], w2 = m->w2[j];
        for (b = 0; b < nb; ++b)
            z[b] = b1;
        for (i = 0; i < m->nin; ++i) {
            const double w = wj[i], *xi = xs + (size_t)i * BLOCK;
            for (b = 0; b < nb; ++b)
                z[b] += w * xi[b];
        }
#pragma omp simd
        for (b = 0; b < nb; ++b)
            acc[b] += w2 * fast_tanh(z[b]);
    }
    for (b = 0; b < nb; ++b)
        y[b] = (acc[b] + 1.0) * half + m->out_lo;
    if (m->out_log)
        for (b = 0; b < nb; ++b)
            y[b] = exp(y[b]);
}

dem_status dem_mlp_eval_many(const dem_mlp *m, const double *x, size_t n, double *y, int num_threads)
{
    long nblocks, blk;
    dem_status st = DEM_OK;
    if (!m || (n && (!x || !y)))
        return DEM_ERR_NULL;
    nblocks = (long)((n + BLOCK - 1) / BLOCK);
#pragma omp parallel num_threads(num_threads > 0 ? num_threads : omp_get_max_threads())
    {
        double *xs = dem_malloc(sizeof(double) * BLOCK * (size_t)m->nin);
        if (!xs) {
#pragma omp atomic write
            st = DEM_ERR_NO_MEMORY;
        }
#pragma omp for schedule(static)
        for (blk = 0; blk < nblocks; ++blk) {
            size_t start = (size_t)blk * BLOCK;
            int nb = (int)(n - start < BLOCK ? n - start : BLOCK);
            if (xs)
                eval_block(m, x + start * (size_t)m->nin, nb, xs, y + start);
        }
        dem_free(xs);
    }
    return st;
}

dem_status dem_mlp_screen(const dem_mlp *const *nets, int num_nets, const double *target, const double *window,
                          const double *x, size_t n, int num_threads, unsigned char *keep, double *predictions,
                          size_t *num_kept, char *err, size_t err_size)
{
    long nblocks, blk;
    size_t kept = 0;
    int k, i, failed = 0;
    if (!nets || num_nets < 1 || !target || !window || (n && (!x || !keep)) || !num_kept) {
        dem_mlp_set_error(err, err_size, "dem_mlp_screen: NULL argument or no nets");
        return DEM_ERR_NULL;
    }
    for (k = 0; k < num_nets; ++k) {
        if (!nets[k]) {
            dem_mlp_set_error(err, err_size, "dem_mlp_screen: net %d is NULL", k);
            return DEM_ERR_NULL;
        }
        if (!isfinite(target[k]) || !isfinite(window[k]) || window[k] < 0) {
            dem_mlp_set_error(err, err_size, "net %d (%s): target %g and window %g must be finite, window >= 0", k,
                              nets[k]->name, target[k], window[k]);
            return DEM_ERR_INVALID_ARGUMENT;
        }
        if (nets[k]->nin != nets[0]->nin) {
            dem_mlp_set_error(err, err_size, "net %d (%s) takes %d inputs, net 0 (%s) takes %d", k, nets[k]->name,
                              nets[k]->nin, nets[0]->name, nets[0]->nin);
            return DEM_ERR_INVALID_ARGUMENT;
        }
        for (i = 0; i < nets[0]->nin; ++i)
            if (strcmp(nets[k]->input_names[i], nets[0]->input_names[i]) != 0) {
                dem_mlp_set_error(err, err_size, "net %d (%s): input %d is '%s', net 0 (%s) has '%s'", k,
                                  nets[k]->name, i + 1, nets[k]->input_names[i], nets[0]->name,
                                  nets[0]->input_names[i]);
                return DEM_ERR_INVALID_ARGUMENT;
            }
    }
    nblocks = (long)((n + BLOCK - 1) / BLOCK);
#pragma omp parallel num_threads(num_threads > 0 ? num_threads : omp_get_max_threads()) reduction(+ : kept, failed)
    {
        double *xs = dem_malloc(sizeof(double) * BLOCK * (size_t)nets[0]->nin);
        double pred[BLOCK];
        unsigned char ok[BLOCK];
        failed += xs == NULL;
#pragma omp for schedule(static)
        for (blk = 0; blk < nblocks; ++blk) {
            size_t start = (size_t)blk * BLOCK;
            int nb = (int)(n - start < BLOCK ? n - start : BLOCK), b, kk;
            if (!xs)
                continue;
            memset(ok, 1, sizeof ok);
            for (kk = 0; kk < num_nets; ++kk) {
                const double tol = window[kk] * fabs(target[kk]);
                eval_block(nets[kk], x + start * (size_t)nets[0]->nin, nb, xs, pred);
                for (b = 0; b < nb; ++b)
                    ok[b] &= (unsigned char)(fabs(pred[b] - target[kk]) <= tol);
                if (predictions)
                    for (b = 0; b < nb; ++b)
                        predictions[(start + (size_t)b) * (size_t)num_nets + (size_t)kk] = pred[b];
            }
            for (b = 0; b < nb; ++b) {
                keep[start + (size_t)b] = ok[b];
                kept += ok[b];
            }
        }
        dem_free(xs);
    }
    if (failed) {
        dem_mlp_set_error(err, err_size, "dem_mlp_screen: out of memory for the thread scratch");
        return DEM_ERR_NO_MEMORY;
    }
    *num_kept = kept;
    return DEM_OK;
}
