/* Contact forces. Each thread owns a contiguous range of rows of the half Verlet list: it
 * sums the forces on the row particles itself and stores the reaction on j per entry; the
 * reactions are gathered later per particle in a fixed order (dem_forces_gather). No atomics
 * and no thread-dependent summation order: results are bitwise identical for any thread count.
 *
 * Speed: the touching pairs of a row range are collected into batches of structure-of-arrays
 * and the contact law runs over a batch in one branch-free loop that the compiler vectorises
 * (AVX2 / AVX-512 clones on x86-64, chosen at load time). Pairs the batch kernel does not
 * cover (CDT or damped EPSD rolling, effects) and the walls take the general contact_law(). */
#include "contact_law.h"
#include <float.h>
#include <math.h>
#ifdef _OPENMP
#include <omp.h>
#endif

static const double image_sign[27][3] = {
    {-1, -1, -1}, {0, -1, -1}, {1, -1, -1}, {-1, 0, -1}, {0, 0, -1}, {1, 0, -1}, {-1, 1, -1}, {0, 1, -1}, {1, 1, -1},
    {-1, -1, 0},  {0, -1, 0},  {1, -1, 0},  {-1, 0, 0},  {0, 0, 0},  {1, 0, 0},  {-1, 1, 0},  {0, 1, 0},  {1, 1, 0},
    {-1, -1, 1},  {0, -1, 1},  {1, -1, 1},  {-1, 0, 1},  {0, 0, 1},  {1, 0, 1},  {-1, 1, 1},  {0, 1, 1},  {1, 1, 1}};

/* Cold path: name the contact of row particle i whose overlap exceeds the limit. */
static dem_status report_runaway(dem_domain *d, int64_t i, double (*shift)[3])
{
    const pair_list *pl = &d->pairs_cur;
    const wall_list *wl = &d->walls_cur;
    const double ratio = d->def.max_overlap_ratio, ri = d->radius[i];
    const char *why = "(time step too large for the stiffness and speeds, or particles inserted into each other)";
    for (int64_t k = pl->start[i]; k < pl->start[i + 1]; k++) {
        int32_t j = pl->j[k];
        double r2 = 0;
        for (int a = 0; a < 3; a++) {
            double u = d->x[3 * i + a] - d->x[3 * j + a] - shift[pl->image[k]][a];
            r2 += u * u;
        }
        double delta = ri + d->radius[j] - sqrt(r2), rmin = ri < d->radius[j] ? ri : d->radius[j];
        if (delta > ratio * rmin)
            return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP,
                            "runaway overlap during step %lld: particles id %lld and id %lld overlap by %g m, %.2f of "
                            "the smaller radius (limit %g) %s",
                            (long long)d->step + 1, (long long)d->id[i], (long long)d->id[j], delta, delta / rmin,
                            ratio, why);
    }
    for (int64_t k = wl->start[i]; k < wl->start[i + 1]; k++) {
        const plane_wall *pw = &d->walls[wl->wall[k]];
        double delta = ri - (d->x[3 * i + pw->def.axis] - pw->def.position) * pw->def.side;
        if (delta > ratio * ri)
            return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP,
                            "runaway overlap during step %lld: particle id %lld overlaps plane wall %d by %g m, %.2f "
                            "of its radius (limit %g) %s",
                            (long long)d->step + 1, (long long)d->id[i], wl->wall[k], delta, delta / ri, ratio, why);
    }
    return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP, "runaway overlap during step %lld at particle id %lld %s",
                    (long long)d->step + 1, (long long)d->id[i], why);
}

#define BATCH 64

/* One batch of touching pairs, structure of arrays. */
typedef struct batch {
    int n;
    const pair_props *pp; /* every pair of a batch has the same material pair */
    int64_t k[BATCH];
    int32_t i[BATCH], j[BATCH];
    double dx[BATCH], dy[BATCH], dz[BATCH], r2[BATCH];
    double ri[BATCH], rj[BATCH], imi[BATCH], imj[BATCH];
    double dv[3][BATCH], wi[3][BATCH], wj[3][BATCH];
    double xi[3][BATCH], mr[3][BATCH];
    double f[3][BATCH], ti[3][BATCH], tj[3][BATCH], delta[BATCH];
} batch;

/* The seed-000 law over a batch (same formulas as contact_law(), written without branches so
 * that it vectorises; selects instead of ifs, identical results). */
DEM_INLINE void batch_law_body(batch *restrict b, double dt, int rolling)
{
    const int n = b->n;
    const pair_props *pp = b->pp;
    const double es = pp->e_star, gs = pp->g_star, damp = pp->damping_factor, stsn = pp->st_over_sn_sqrt;
    const double mus = pp->def.friction, mur = pp->def.rolling_friction;
    const int epsd2 = pp->def.rolling_model == DEM_ROLLING_EPSD2;
    for (int c = 0; c < n; c++) {
        const double r = sqrt(b->r2[c]);
        const double inv_r = 1.0 / r;
        const double nx = b->dx[c] * inv_r, ny = b->dy[c] * inv_r, nz = b->dz[c] * inv_r;
        const double ri = b->ri[c], rj = b->rj[c];
        const double delta = ri + rj - r;
        const double ci = ri - 0.5 * delta, cj = rj - 0.5 * delta;
        const double wix = b->wi[0][c], wiy = b->wi[1][c], wiz = b->wi[2][c];
        const double wjx = b->wj[0][c], wjy = b->wj[1][c], wjz = b->wj[2][c];
        const double swx = ci * wix + cj * wjx, swy = ci * wiy + cj * wjy, swz = ci * wiz + cj * wjz;
        const double vcx = b->dv[0][c] - (swy * nz - swz * ny);
        const double vcy = b->dv[1][c] - (swz * nx - swx * nz);
        const double vcz = b->dv[2][c] - (swx * ny - swy * nx);
        const double reff = ri * rj / (ri + rj);
        const double meff = 1.0 / (b->imi[c] + b->imj[c]);
        const double sqrt_rd = sqrt(reff * delta);
        const double sn = 2.0 * es * sqrt_rd;
        const double kn = (2.0 / 3.0) * sn;
        const double kt = 8.0 * gs * sqrt_rd;
        const double gn = damp * sqrt(sn * meff);
        const double gt = gn * stsn;
        const double vn = vcx * nx + vcy * ny + vcz * nz;
        const double fn0 = kn * delta - gn * vn;
        const double fn = fn0 > 0.0 ? fn0 : 0.0;
        const double vtx = vcx - vn * nx, vty = vcy - vn * ny, vtz = vcz - vn * nz;
        /* tangential spring: rotate into the tangent plane keeping its length, then load */
        double hx = b->xi[0][c], hy = b->xi[1][c], hz = b->xi[2][c];
        const double h2 = hx * hx + hy * hy + hz * hz;
        const double hn = hx * nx + hy * ny + hz * nz;
        hx -= hn * nx;
        hy -= hn * ny;
        hz -= hn * nz;
        const double p2 = hx * hx + hy * hy + hz * hz;
        const double sp = sqrt(h2 / (p2 > DBL_MIN ? p2 : DBL_MIN));
        hx = hx * sp + vtx * dt;
        hy = hy * sp + vty * dt;
        hz = hz * sp + vtz * dt;
        double ftx = -kt * hx - gt * vtx, fty = -kt * hy - gt * vty, ftz = -kt * hz - gt * vtz;
        const double ft2 = ftx * ftx + fty * fty + ftz * ftz;
        const double fm = mus * fn;
        const int capped = ft2 > fm * fm;
        const double sc_c = fm / sqrt(capped ? ft2 : 1.0);
        const double sc = capped ? sc_c : 1.0;
        ftx *= sc;
        fty *= sc;
        ftz *= sc;
        const double ikt = -1.0 / kt;
        const double cx = (ftx + gt * vtx) * ikt, cy = (fty + gt * vty) * ikt, cz = (ftz + gt * vtz) * ikt;
        b->xi[0][c] = capped ? cx : hx;
        b->xi[1][c] = capped ? cy : hy;
        b->xi[2][c] = capped ? cz : hz;
        double mx = 0.0, my = 0.0, mz = 0.0;
        if (rolling) { /* elastic-plastic spring (EPSD2: k_t R*^2, EPSD: 2.25 k_n mu_r^2 R*^2) */
            const double wrx0 = wix - wjx, wry0 = wiy - wjy, wrz0 = wiz - wjz;
            const double wn = wrx0 * nx + wry0 * ny + wrz0 * nz;
            const double wrx = wrx0 - wn * nx, wry = wry0 - wn * ny, wrz = wrz0 - wn * nz;
            const double mmax = mur * reff * fn;
            const double kr = epsd2 ? kt * reff * reff : 2.25 * kn * mur * mur * reff * reff;
            mx = b->mr[0][c];
            my = b->mr[1][c];
            mz = b->mr[2][c];
            const double m2o = mx * mx + my * my + mz * mz;
            const double mn = mx * nx + my * ny + mz * nz;
            mx -= mn * nx;
            my -= mn * ny;
            mz -= mn * nz;
            const double q2 = mx * mx + my * my + mz * mz;
            const double sq = sqrt(m2o / (q2 > DBL_MIN ? q2 : DBL_MIN));
            mx = mx * sq - kr * wrx * dt;
            my = my * sq - kr * wry * dt;
            mz = mz * sq - kr * wrz * dt;
            const double m2 = mx * mx + my * my + mz * mz;
            const int mcap = m2 > mmax * mmax;
            const double sm_c = mmax / sqrt(mcap ? m2 : 1.0);
            const double sm = mcap ? sm_c : 1.0;
            mx *= sm;
            my *= sm;
            mz *= sm;
            b->mr[0][c] = mx;
            b->mr[1][c] = my;
            b->mr[2][c] = mz;
        }
        b->f[0][c] = fn * nx + ftx;
        b->f[1][c] = fn * ny + fty;
        b->f[2][c] = fn * nz + ftz;
        const double crx = ny * ftz - nz * fty, cry = nz * ftx - nx * ftz, crz = nx * fty - ny * ftx;
        b->ti[0][c] = -ci * crx + mx;
        b->ti[1][c] = -ci * cry + my;
        b->ti[2][c] = -ci * crz + mz;
        b->tj[0][c] = -cj * crx - mx;
        b->tj[1][c] = -cj * cry - my;
        b->tj[2][c] = -cj * crz - mz;
        b->delta[c] = delta;
    }
}

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(DEM_NO_CLONES)
#define DEM_CLONES __attribute__((target_clones("arch=icelake-server", "avx2", "default")))
#else
#define DEM_CLONES
#endif

DEM_CLONES static void batch_law_rolling(batch *restrict b, double dt) { batch_law_body(b, dt, 1); }
DEM_CLONES static void batch_law_sliding(batch *restrict b, double dt) { batch_law_body(b, dt, 0); }

typedef struct force_ctx {
    dem_domain *d;
    double dt;
    double shift[27][3];
} force_ctx;

/* Run the batch kernel, the general law for the slow pairs, then accumulate in batch order. */
static void flush_batch(const force_ctx *fc, batch *b, int64_t *bad)
{
    dem_domain *d = fc->d;
    pair_list *pl = &d->pairs_cur;
    const int slow = !b->pp->fast;
    if (slow) { /* the general law runs below, contact by contact */
    } else if (b->pp->def.rolling_friction > 0.0) {
        batch_law_rolling(b, fc->dt);
    } else {
        batch_law_sliding(b, fc->dt);
    }
    const double ratio = d->def.max_overlap_ratio;
    int64_t cur = -1;
    double fs[3] = {0, 0, 0}, ts[3] = {0, 0, 0};
    for (int c = 0; c < b->n; c++) {
        const int64_t k = b->k[c];
        const int32_t i = b->i[c];
        if (slow) {
            contact_in in;
            const double r = sqrt(b->r2[c]), inv_r = 1.0 / r;
            in.n[0] = b->dx[c] * inv_r;
            in.n[1] = b->dy[c] * inv_r;
            in.n[2] = b->dz[c] * inv_r;
            in.overlap = b->ri[c] + b->rj[c] - r;
            in.distance = r;
            const double ci = b->ri[c] - 0.5 * in.overlap, cj = b->rj[c] - 0.5 * in.overlap;
            double sw[3];
            for (int a = 0; a < 3; a++) sw[a] = ci * b->wi[a][c] + cj * b->wj[a][c];
            in.vc[0] = b->dv[0][c] - (sw[1] * in.n[2] - sw[2] * in.n[1]);
            in.vc[1] = b->dv[1][c] - (sw[2] * in.n[0] - sw[0] * in.n[2]);
            in.vc[2] = b->dv[2][c] - (sw[0] * in.n[1] - sw[1] * in.n[0]);
            for (int a = 0; a < 3; a++) in.wrel[a] = b->wi[a][c] - b->wj[a][c];
            in.r_eff = b->ri[c] * b->rj[c] / (b->ri[c] + b->rj[c]);
            in.m_eff = 1.0 / (b->imi[c] + b->imj[c]);
            in.radius_i = b->ri[c];
            in.radius_j = b->rj[c];
            in.inv_mass_i = b->imi[c];
            in.inv_mass_j = b->imj[c];
            contact_out o;
            contact_law(b->pp, &in, fc->dt, pl->xi + 3 * k, pl->mr + 3 * k, &o);
            for (int a = 0; a < 3; a++) {
                b->f[a][c] = o.force[a];
                b->ti[a][c] = -ci * o.cross[a] + o.mr[a];
                b->tj[a][c] = -cj * o.cross[a] - o.mr[a];
            }
            b->delta[c] = in.overlap;
        } else {
            for (int a = 0; a < 3; a++) {
                pl->xi[3 * k + a] = b->xi[a][c];
                pl->mr[3 * k + a] = b->mr[a][c];
            }
        }
        if (i != cur) { /* rows arrive in order: sum in registers, store when the row changes */
            if (cur >= 0)
                for (int a = 0; a < 3; a++) {
                    d->f[3 * cur + a] = fs[a];
                    d->t[3 * cur + a] = ts[a];
                }
            cur = i;
            for (int a = 0; a < 3; a++) {
                fs[a] = d->f[3 * i + a];
                ts[a] = d->t[3 * i + a];
            }
        }
        double *pf = d->pair_force + 3 * k, *ptj = d->pair_torque_j + 3 * k;
        for (int a = 0; a < 3; a++) {
            fs[a] += b->f[a][c];
            ts[a] += b->ti[a][c];
            pf[a] = -b->f[a][c];
            ptj[a] = b->tj[a][c];
        }
        pl->active[k] = 1;
        const double rmin = b->ri[c] < b->rj[c] ? b->ri[c] : b->rj[c];
        if (b->delta[c] > ratio * rmin && i < *bad) *bad = i;
    }
    if (cur >= 0)
        for (int a = 0; a < 3; a++) {
            d->f[3 * cur + a] = fs[a];
            d->t[3 * cur + a] = ts[a];
        }
    b->n = 0;
}

/* Plane-wall contacts of particle i, added to f/t after its pair contacts. */
static void wall_contacts(const force_ctx *fc, int64_t i, int64_t *bad)
{
    dem_domain *d = fc->d;
    const wall_list *wl = &d->walls_cur;
    const double *xi_ = d->x + 3 * i, *vi = d->v + 3 * i, *wi = d->w + 3 * i;
    const double ri = d->radius[i];
    const pair_props *row_pairs = d->pairs + (size_t)d->mat[i] * d->n_materials;
    double *f = d->f + 3 * i, *t = d->t + 3 * i;
    for (int64_t k = wl->start[i]; k < wl->start[i + 1]; k++) {
        const plane_wall *pw = &d->walls[wl->wall[k]];
        const double dist = (xi_[pw->def.axis] - pw->def.position) * pw->def.side;
        double *hxi = wl->xi + 3 * k, *hmr = wl->mr + 3 * k, *wf = wl->force + 3 * k;
        if (dist >= ri) {
            hxi[0] = hxi[1] = hxi[2] = hmr[0] = hmr[1] = hmr[2] = 0.0;
            wf[0] = wf[1] = wf[2] = 0.0;
            continue;
        }
        contact_in c;
        for (int a = 0; a < 3; a++) c.n[a] = pw->normal[a];
        c.overlap = ri - dist;
        if (c.overlap > d->def.max_overlap_ratio * ri && i < *bad) *bad = i;
        c.distance = dist;
        const double ci = ri - 0.5 * c.overlap;
        const double *vw = pw->def.velocity;
        c.vc[0] = vi[0] - vw[0] - ci * (wi[1] * c.n[2] - wi[2] * c.n[1]);
        c.vc[1] = vi[1] - vw[1] - ci * (wi[2] * c.n[0] - wi[0] * c.n[2]);
        c.vc[2] = vi[2] - vw[2] - ci * (wi[0] * c.n[1] - wi[1] * c.n[0]);
        for (int a = 0; a < 3; a++) c.wrel[a] = wi[a];
        c.r_eff = ri;
        c.m_eff = 1.0 / d->inv_mass[i];
        c.radius_i = ri;
        c.radius_j = 0.0;
        c.inv_mass_i = d->inv_mass[i];
        c.inv_mass_j = 0.0;
        contact_out o;
        contact_law(&row_pairs[pw->def.material], &c, fc->dt, hxi, hmr, &o);
        for (int a = 0; a < 3; a++) {
            f[a] += o.force[a];
            t[a] += -ci * o.cross[a] + o.mr[a];
            wf[a] = o.force[a];
        }
    }
}

/* Gather the inputs of the collected pairs (positions were taken when testing the distance). */
static void fill_batch(const force_ctx *fc, batch *b)
{
    const dem_domain *d = fc->d;
    const pair_list *pl = &d->pairs_cur;
    const double *v = d->v, *w = d->w, *rad = d->radius, *im = d->inv_mass;
    for (int c = 0; c < b->n; c++) {
        const int64_t k = b->k[c];
        const int32_t i = b->i[c], j = b->j[c];
        b->ri[c] = rad[i];
        b->rj[c] = rad[j];
        b->imi[c] = im[i];
        b->imj[c] = im[j];
        for (int a = 0; a < 3; a++) {
            b->dv[a][c] = v[3 * i + a] - v[3 * j + a];
            b->wi[a][c] = w[3 * i + a];
            b->wj[a][c] = w[3 * j + a];
            b->xi[a][c] = pl->xi[3 * k + a];
            b->mr[a][c] = pl->mr[3 * k + a];
        }
    }
}

/* Entries whose contact ended: forget the springs, clear the force slots (once). */
static void clear_lost(dem_domain *d, const int64_t *lost, int n_lost)
{
    pair_list *pl = &d->pairs_cur;
    for (int q = 0; q < n_lost; q++) {
        const int64_t k = lost[q];
        double *z[4] = {pl->xi + 3 * k, pl->mr + 3 * k, d->pair_force + 3 * k, d->pair_torque_j + 3 * k};
        for (int u = 0; u < 4; u++) z[u][0] = z[u][1] = z[u][2] = 0.0;
        pl->active[k] = 0;
    }
}

/* Forces of rows [r0, r1): pairs through batches, then walls. The distance test appends
 * without a branch (write, then advance by the test's outcome): whether a neighbour touches
 * is unpredictable, and a mispredicted branch per entry would cost more than the contact law. */
static void rows_forces(const force_ctx *fc, int64_t r0, int64_t r1, batch *b, int64_t *bad)
{
    dem_domain *d = fc->d;
    pair_list *pl = &d->pairs_cur;
    const double *x = d->x, *rad = d->radius;
    const uint8_t *active = pl->active;
    int64_t lost[BATCH];
    int n_lost = 0;
    for (int64_t i = r0; i < r1; i++)
        for (int a = 0; a < 3; a++) d->f[3 * i + a] = d->t[3 * i + a] = 0.0;
    int nb = 0; /* kept in a register: b->n would be reloaded after every store into b */
    const int32_t *mat = d->mat;
    const int nm = d->n_materials;
    b->pp = d->pairs;
    for (int64_t i = r0; i < r1; i++) {
        const double xi0 = x[3 * i], xi1 = x[3 * i + 1], xi2 = x[3 * i + 2], ri = rad[i];
        const pair_props *row_pairs = d->pairs + (size_t)mat[i] * nm;
        const int64_t k_end = pl->start[i + 1];
        for (int64_t k = pl->start[i]; k < k_end; k++) {
            const int32_t j = pl->j[k];
            const pair_props *pp = &row_pairs[mat[j]];
            if ((pp != b->pp) & (nb > 0)) { /* a batch holds one material pair */
                b->n = nb;
                fill_batch(fc, b);
                flush_batch(fc, b, bad);
                nb = 0;
            }
            b->pp = pp;
            const double *sh = fc->shift[pl->image[k]];
            const double dx = xi0 - (x[3 * j] + sh[0]), dy = xi1 - (x[3 * j + 1] + sh[1]),
                         dz = xi2 - (x[3 * j + 2] + sh[2]);
            const double rsum = ri + rad[j], r2 = dx * dx + dy * dy + dz * dz;
            const int touching = r2 < rsum * rsum;
            b->k[nb] = k;
            b->i[nb] = (int32_t)i;
            b->j[nb] = j;
            b->dx[nb] = dx;
            b->dy[nb] = dy;
            b->dz[nb] = dz;
            b->r2[nb] = r2;
            nb += touching;
            lost[n_lost] = k;
            n_lost += (!touching) & active[k];
            if (nb == BATCH) {
                b->n = nb;
                fill_batch(fc, b);
                flush_batch(fc, b, bad);
                nb = 0;
            }
            if (n_lost == BATCH) {
                clear_lost(d, lost, n_lost);
                n_lost = 0;
            }
        }
    }
    if (nb) {
        b->n = nb;
        fill_batch(fc, b);
        flush_batch(fc, b, bad);
    }
    clear_lost(d, lost, n_lost);
    for (int64_t i = r0; i < r1; i++) wall_contacts(fc, i, bad);
}

/* dt_hist: time increment for the spring histories (0 for a force refresh without motion). */
dem_status dem_forces_compute(dem_domain *d, double dt_hist)
{
    const int64_t n = d->n;
    const int nt = d->def.num_threads;
    force_ctx fc;
    fc.d = d;
    fc.dt = dt_hist;
    for (int s = 0; s < 27; s++)
        for (int a = 0; a < 3; a++) fc.shift[s][a] = image_sign[s][a] * (d->def.hi[a] - d->def.lo[a]);
    int64_t bad = INT64_MAX;
#pragma omp parallel num_threads(nt) reduction(min : bad)
    {
        batch b;
        int tid = 0, nth = 1;
#ifdef _OPENMP
        tid = omp_get_thread_num();
        nth = omp_get_num_threads();
#endif
        int64_t r0 = n * tid / nth, r1 = n * (tid + 1) / nth;
        rows_forces(&fc, r0, r1, &b, &bad);
    }
    if (bad != INT64_MAX) return report_runaway(d, bad, fc.shift);
    return DEM_OK;
}
