/* The force sweep: pair contact forces, force gathering and the Verlet kicks/drift in one
 * pass over the particles, so each particle's data is used while it is still in cache.
 *
 * The half Verlet list pairs particle i (its row) with partners j that come later in memory
 * order (the forward half of the cell stencil), except across periodic faces. Processing rows
 * in order, particle p's forces are therefore complete once row p is done: its own row gives
 * the i-side, and every entry naming p as partner was in an earlier row, whose reaction waits
 * in a per-entry slot. p is then finished at once — reactions gathered, walls added, closing
 * half kick, opening half kick and drift — and nothing later reads its old state.
 * A particle named by a later row (periodic wrap) or by another thread's rows is "deferred":
 * finished after all rows are done. The summation order of every force (own row in list
 * order, then reactions in list order, then walls) does not depend on the thread count or on
 * deferral, so results are bitwise identical for any number of threads. */
#include "contact_law.h"
#include "sweep.h"
#include <float.h>
#include <math.h>
#ifdef _OPENMP
#include <omp.h>
#endif

typedef struct sweep_ctx {
    dem_domain *d;
    double dt_hist;   /* spring history increment (0: refresh without motion) */
    sweep_mode mode;
    double shift[27][3];
    double lo[3], hi[3]; /* closed-axis bounds (+-DBL_MAX on periodic axes) */
} sweep_ctx;

/* Contacts of row i: forces on i summed into f/t (list order), reactions into the slots. */
static inline void row_forces(const sweep_ctx *c, int64_t i, double *f, double *t, int64_t *bad_pair)
{
    dem_domain *d = c->d;
    pair_list *pl = &d->pairs_cur;
    const double *x = d->x, *v = d->v, *w = d->w, *rad = d->radius, *im = d->inv_mass;
    const double xi0 = x[3 * i], xi1 = x[3 * i + 1], xi2 = x[3 * i + 2], ri = rad[i], imi = im[i];
    const double *vi = v + 3 * i, *wi = w + 3 * i;
    const pair_props *row_pairs = d->pairs + (size_t)d->mat[i] * d->n_materials;
    const double ratio = d->def.max_overlap_ratio;
    double f0 = 0, f1 = 0, f2 = 0, t0 = 0, t1 = 0, t2 = 0;
    const int64_t k1 = pl->start[i + 1];
    for (int64_t k = pl->start[i]; k < k1; k++) {
        const int32_t j = pl->j[k];
        const double *sh = c->shift[pl->image[k]];
        const double dx = xi0 - (x[3 * j] + sh[0]), dy = xi1 - (x[3 * j + 1] + sh[1]), dz = xi2 - (x[3 * j + 2] + sh[2]);
        const double rj = rad[j], rsum = ri + rj;
        const double r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= rsum * rsum) {
            if (pl->active[k]) { /* contact ended: forget the springs, clear the slot once */
                for (int a = 0; a < 6; a++) pl->hist[6 * k + a] = d->slot[6 * k + a] = 0.0;
                pl->active[k] = 0;
            }
            continue;
        }
        const double r = sqrt(r2), inv_r = 1.0 / r;
        contact_in in;
        in.n[0] = dx * inv_r;
        in.n[1] = dy * inv_r;
        in.n[2] = dz * inv_r;
        in.overlap = rsum - r;
        in.distance = r;
        if (in.overlap > ratio * (ri < rj ? ri : rj) && k < *bad_pair) *bad_pair = k;
        const double ci = ri - 0.5 * in.overlap, cj = rj - 0.5 * in.overlap; /* lever arms */
        const double *vj = v + 3 * j, *wj = w + 3 * j;
        const double sw0 = ci * wi[0] + cj * wj[0], sw1 = ci * wi[1] + cj * wj[1], sw2 = ci * wi[2] + cj * wj[2];
        in.vc[0] = vi[0] - vj[0] - (sw1 * in.n[2] - sw2 * in.n[1]);
        in.vc[1] = vi[1] - vj[1] - (sw2 * in.n[0] - sw0 * in.n[2]);
        in.vc[2] = vi[2] - vj[2] - (sw0 * in.n[1] - sw1 * in.n[0]);
        in.wrel[0] = wi[0] - wj[0];
        in.wrel[1] = wi[1] - wj[1];
        in.wrel[2] = wi[2] - wj[2];
        in.r_eff = ri * rj / rsum;
        in.m_eff = 1.0 / (imi + im[j]);
        in.radius_i = ri;
        in.radius_j = rj;
        in.inv_mass_i = imi;
        in.inv_mass_j = im[j];
        double *h = pl->hist + 6 * k, *sl = d->slot + 6 * k;
        contact_out o;
        contact_law(&row_pairs[d->mat[j]], &in, c->dt_hist, h, h + 3, &o);
        for (int a = 0; a < 3; a++) {
            sl[a] = o.force[a];
            sl[3 + a] = -cj * o.cross[a] - o.mr[a];
        }
        pl->active[k] = 1;
        f0 += o.force[0];
        f1 += o.force[1];
        f2 += o.force[2];
        t0 += -ci * o.cross[0] + o.mr[0];
        t1 += -ci * o.cross[1] + o.mr[1];
        t2 += -ci * o.cross[2] + o.mr[2];
    }
    f[0] = f0;
    f[1] = f1;
    f[2] = f2;
    t[0] = t0;
    t[1] = t1;
    t[2] = t2;
}

/* Finish particle p: add the reactions (list order) and walls to its row sums, store the
 * forces, then the kicks and drift the mode asks for. */
static inline void finish(const sweep_ctx *c, int64_t p, double *f, double *t, sweep_result *res)
{
    dem_domain *d = c->d;
    const int32_t *te = d->trans_entry;
    for (int64_t q = d->trans_start[p]; q < d->trans_start[p + 1]; q++) {
        const double *sl = d->slot + 6 * (int64_t)te[q];
        f[0] -= sl[0];
        f[1] -= sl[1];
        f[2] -= sl[2];
        t[0] += sl[3];
        t[1] += sl[4];
        t[2] += sl[5];
    }
    if (d->walls_cur.start[p] < d->walls_cur.start[p + 1]) dem_wall_contacts(d, p, c->dt_hist, f, t, &res->bad_wall);
    if (d->tris_cur.start[p] < d->tris_cur.start[p + 1]) dem_mesh_contacts(d, p, c->dt_hist, f, t, &res->bad_wall);
    double *fp = d->f + 3 * p, *tp = d->t + 3 * p;
    for (int a = 0; a < 3; a++) {
        fp[a] = f[a];
        tp[a] = t[a];
    }
    if (c->mode == SWEEP_FORCES) return;
    const double half = 0.5 * d->def.dt, *g = d->def.gravity;
    const double imp = d->inv_mass[p], iip = d->inv_inertia[p];
    double *vp = d->v + 3 * p, *wp = d->w + 3 * p;
    double vl[3], wl[3];
    for (int a = 0; a < 3; a++) { /* closing half kick */
        vl[a] = vp[a] + half * (f[a] * imp + g[a]);
        wl[a] = wp[a] + half * t[a] * iip;
    }
    if (c->mode == SWEEP_CLOSE_OPEN) dem_open_step(d, p, f, t, vl, wl, c->lo, c->hi, res);
    for (int a = 0; a < 3; a++) {
        vp[a] = vl[a];
        wp[a] = wl[a];
    }
}

/* Opening half kick and drift of particle p (shared with the first step of a call). */
void dem_open_step(dem_domain *d, int64_t p, const double *f, const double *t, double *vl, double *wl,
                   const double *lo, const double *hi, sweep_result *res)
{
    const double dt = d->def.dt, half = 0.5 * dt, *g = d->def.gravity;
    const double imp = d->inv_mass[p], iip = d->inv_inertia[p];
    double *xp = d->x + 3 * p;
    const double *xb = d->x_build + 3 * p;
    double disp2 = 0.0, sum = 0.0;
    int in = 1;
    for (int a = 0; a < 3; a++) {
        vl[a] += half * (f[a] * imp + g[a]);
        wl[a] += half * t[a] * iip;
        xp[a] += dt * vl[a];
        const double u = xp[a] - xb[a];
        disp2 += u * u;
        sum += xp[a] + wl[a];
        in &= (xp[a] >= lo[a]) & (xp[a] <= hi[a]);
    }
    if (disp2 > res->maxdisp2) res->maxdisp2 = disp2;
    if (!(sum - sum == 0.0)) { /* NaN or inf somewhere in x, v (through x) or w */
        if (p < res->bad_nan) res->bad_nan = p;
    } else if (!in && p < res->bad_out) {
        res->bad_out = p;
    }
}

void dem_sweep_bounds(const dem_domain *d, double *lo, double *hi)
{
    for (int a = 0; a < 3; a++) {
        lo[a] = d->def.periodic[a] ? -DBL_MAX : d->def.lo[a];
        hi[a] = d->def.periodic[a] ? DBL_MAX : d->def.hi[a];
    }
}

void dem_sweep_result_init(sweep_result *r)
{
    r->maxdisp2 = 0.0;
    r->bad_nan = r->bad_out = r->bad_wall = r->bad_pair = INT64_MAX;
}

sweep_result dem_sweep(dem_domain *d, double dt_hist, sweep_mode mode)
{
    sweep_ctx c;
    c.d = d;
    c.dt_hist = dt_hist;
    c.mode = mode;
    for (int s = 0; s < 27; s++)
        for (int a = 0; a < 3; a++) c.shift[s][a] = dem_image_sign[s][a] * (d->def.hi[a] - d->def.lo[a]);
    dem_sweep_bounds(d, c.lo, c.hi);
    const int64_t n = d->n;
    double maxdisp2 = 0.0;
    int64_t bad_nan = INT64_MAX, bad_out = INT64_MAX, bad_wall = INT64_MAX, bad_pair = INT64_MAX;
#pragma omp parallel num_threads(d->def.num_threads) reduction(max : maxdisp2) \
    reduction(min : bad_nan, bad_out, bad_wall, bad_pair)
    {
        int tid = 0, nth = 1;
#ifdef _OPENMP
        tid = omp_get_thread_num();
        nth = omp_get_num_threads();
#endif
        const int64_t r0 = n * tid / nth, r1 = n * (tid + 1) / nth;
        sweep_result res;
        dem_sweep_result_init(&res);
        for (int64_t i = r0; i < r1; i++) {
            double f[3], t[3];
            row_forces(&c, i, f, t, &res.bad_pair);
            /* named only by rows of this thread up to i: finish now; else park the row sums
             * in the force arrays and finish after the barrier */
            if (d->trans_lo[i] >= r0 && d->trans_hi[i] <= i) {
                finish(&c, i, f, t, &res);
            } else {
                for (int a = 0; a < 3; a++) {
                    d->f[3 * i + a] = f[a];
                    d->t[3 * i + a] = t[a];
                }
            }
        }
#pragma omp barrier
        for (int64_t i = r0; i < r1; i++) {
            if (d->trans_lo[i] >= r0 && d->trans_hi[i] <= i) continue;
            double f[3] = {d->f[3 * i], d->f[3 * i + 1], d->f[3 * i + 2]};
            double t[3] = {d->t[3 * i], d->t[3 * i + 1], d->t[3 * i + 2]};
            finish(&c, i, f, t, &res);
        }
        maxdisp2 = res.maxdisp2;
        bad_nan = res.bad_nan;
        bad_out = res.bad_out;
        bad_wall = res.bad_wall;
        bad_pair = res.bad_pair;
    }
    sweep_result out = {maxdisp2, bad_nan, bad_out, bad_wall, bad_pair};
    return out;
}
