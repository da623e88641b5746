/* Contact forces.
 *
 * Pairs: one kernel runs over the entries of the half Verlet list in order, touching or not,
 * without branches, so the compiler vectorises it (AVX2 / AVX-512 clones on x86-64, chosen at
 * load time). It reads the histories and writes the force and torques of each entry into
 * per-entry slots (structure of arrays); a non-touching entry gets zeros and a reset history.
 * Each particle then sums its slots in a fixed order (dem_forces_gather): no atomics and no
 * thread-dependent summation order, so results are bitwise identical for any thread count.
 * Pairs the kernel does not cover (CDT or damped EPSD rolling, effects) are redone by the
 * general contact_law(); so are the plane walls (dem_wall_contacts). */
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

/* What the kernel reads, gathered once per call. */
typedef struct kernel_args {
    const double *x, *v, *w, *rad, *im;
    const int32_t *mat, *row, *jj;
    const uint8_t *image;
    double *xi[3], *mr[3], *pf[3], *pti[3], *ptj[3];
    double sx[27], sy[27], sz[27]; /* periodic shifts by image code */
    const pair_props *pp;          /* uniform kernel: the one material pair */
    double dt, ratio;
} kernel_args;

#if defined(__GNUC__) && !defined(__clang__)
#define DEM_IVDEP _Pragma("GCC ivdep") /* the slots of different entries never alias */
#else
#define DEM_IVDEP
#endif

/* The seed-000 law (same formulas as contact_law(), branch-free: selects instead of ifs)
 * over entries [k0, k1) for one material pair. Returns 1 if an overlap exceeds the runaway
 * limit (the caller then finds which). */
DEM_INLINE int pair_kernel_body(const kernel_args *restrict a, int64_t k0, int64_t k1, int rolling)
{
    const pair_props *pp = a->pp;
    const double es = pp->e_star, gs = pp->g_star, damp = pp->damping_factor, stsn = pp->st_over_sn_sqrt;
    const double mus = pp->def.friction, mur = pp->def.rolling_friction, dt = a->dt, ratio = a->ratio;
    const int epsd2 = pp->def.rolling_model == DEM_ROLLING_EPSD2;
    const double *restrict x = a->x, *restrict v = a->v, *restrict w = a->w, *restrict rad = a->rad,
                           *restrict im = a->im;
    const int32_t *restrict row = a->row, *restrict jj = a->jj;
    const uint8_t *restrict image = a->image;
    double *restrict xi0 = a->xi[0], *restrict xi1 = a->xi[1], *restrict xi2 = a->xi[2];
    double *restrict mr0 = a->mr[0], *restrict mr1 = a->mr[1], *restrict mr2 = a->mr[2];
    double *restrict pf0 = a->pf[0], *restrict pf1 = a->pf[1], *restrict pf2 = a->pf[2];
    double *restrict pti0 = a->pti[0], *restrict pti1 = a->pti[1], *restrict pti2 = a->pti[2];
    double *restrict ptj0 = a->ptj[0], *restrict ptj1 = a->ptj[1], *restrict ptj2 = a->ptj[2];
    const double *restrict sxp = a->sx, *restrict syp = a->sy, *restrict szp = a->sz;
    int bad = 0;
    DEM_IVDEP
    for (int64_t k = k0; k < k1; k++) {
        const int64_t i = row[k], j = jj[k];
        const int img = image[k];
        const double dx = x[3 * i] - (x[3 * j] + sxp[img]);
        const double dy = x[3 * i + 1] - (x[3 * j + 1] + syp[img]);
        const double dz = x[3 * i + 2] - (x[3 * j + 2] + szp[img]);
        const double ri = rad[i], rj = rad[j];
        const double r2 = dx * dx + dy * dy + dz * dz;
        const double rsum = ri + rj;
        const int touching = r2 < rsum * rsum;
        const double r = sqrt(r2);
        const double inv_r = 1.0 / r;
        const double nx = dx * inv_r, ny = dy * inv_r, nz = dz * inv_r;
        const double delta0 = rsum - r;
        const double delta = touching ? delta0 : 0.0; /* keeps the arithmetic finite when apart */
        const double rmin = ri < rj ? ri : rj;
        bad |= delta > ratio * rmin;
        const double ci = ri - 0.5 * delta, cj = rj - 0.5 * delta;
        const double wix = w[3 * i], wiy = w[3 * i + 1], wiz = w[3 * i + 2];
        const double wjx = w[3 * j], wjy = w[3 * j + 1], wjz = w[3 * j + 2];
        const double swx = ci * wix + cj * wjx, swy = ci * wiy + cj * wjy, swz = ci * wiz + cj * wjz;
        const double vcx = v[3 * i] - v[3 * j] - (swy * nz - swz * ny);
        const double vcy = v[3 * i + 1] - v[3 * j + 1] - (swz * nx - swx * nz);
        const double vcz = v[3 * i + 2] - v[3 * j + 2] - (swx * ny - swy * nx);
        const double reff = ri * rj / rsum;
        const double meff = 1.0 / (im[i] + im[j]);
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
        double hx = xi0[k], hy = xi1[k], hz = xi2[k];
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
        const double ikt = -1.0 / (kt > 0.0 ? kt : 1.0);
        const double cx = (ftx + gt * vtx) * ikt, cy = (fty + gt * vty) * ikt, cz = (ftz + gt * vtz) * ikt;
        xi0[k] = touching ? (capped ? cx : hx) : 0.0;
        xi1[k] = touching ? (capped ? cy : hy) : 0.0;
        xi2[k] = touching ? (capped ? cz : hz) : 0.0;
        double mx = 0.0, my = 0.0, mz = 0.0;
        if (rolling) { /* elastic-plastic spring (EPSD2: k_t R*^2, EPSD: 2.25 k_n mu_r^2 R*^2) */
            const double wrx0 = wix - wjx, wry0 = wiy - wjy, wrz0 = wiz - wjz;
            const double wn = wrx0 * nx + wry0 * ny + wrz0 * nz;
            const double wrx = wrx0 - wn * nx, wry = wry0 - wn * ny, wrz = wrz0 - wn * nz;
            const double mmax = mur * reff * fn;
            const double kr = epsd2 ? kt * reff * reff : 2.25 * kn * mur * mur * reff * reff;
            mx = mr0[k];
            my = mr1[k];
            mz = mr2[k];
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
            mx = touching ? mx * sm : 0.0;
            my = touching ? my * sm : 0.0;
            mz = touching ? mz * sm : 0.0;
            mr0[k] = mx;
            mr1[k] = my;
            mr2[k] = mz;
        }
        ftx = touching ? ftx : 0.0;
        fty = touching ? fty : 0.0;
        ftz = touching ? ftz : 0.0;
        pf0[k] = fn * nx + ftx; /* fn is 0 when apart */
        pf1[k] = fn * ny + fty;
        pf2[k] = fn * nz + ftz;
        const double crx = ny * ftz - nz * fty, cry = nz * ftx - nx * ftz, crz = nx * fty - ny * ftx;
        pti0[k] = -ci * crx + mx;
        pti1[k] = -ci * cry + my;
        pti2[k] = -ci * crz + mz;
        ptj0[k] = -cj * crx - mx;
        ptj1[k] = -cj * cry - my;
        ptj2[k] = -cj * crz - mz;
    }
    return bad;
}

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(DEM_NO_CLONES)
#define DEM_CLONES __attribute__((target_clones("arch=icelake-server", "avx2", "default")))
#else
#define DEM_CLONES
#endif

DEM_CLONES static int pair_kernel_rolling(const kernel_args *a, int64_t k0, int64_t k1)
{
    return pair_kernel_body(a, k0, k1, 1);
}

DEM_CLONES static int pair_kernel_sliding(const kernel_args *a, int64_t k0, int64_t k1)
{
    return pair_kernel_body(a, k0, k1, 0);
}

/* The general law for entry k (pairs the kernel does not cover). */
static void general_pair(dem_domain *d, const kernel_args *a, int64_t k, const pair_props *pp)
{
    pair_list *pl = &d->pairs_cur;
    const int64_t i = pl->row[k], j = pl->j[k];
    const int img = pl->image[k];
    const double dx = d->x[3 * i] - (d->x[3 * j] + a->sx[img]);
    const double dy = d->x[3 * i + 1] - (d->x[3 * j + 1] + a->sy[img]);
    const double dz = d->x[3 * i + 2] - (d->x[3 * j + 2] + a->sz[img]);
    const double ri = d->radius[i], rj = d->radius[j], r = sqrt(dx * dx + dy * dy + dz * dz);
    double xi[3], mr[3];
    contact_out o;
    contact_in in;
    if (r >= ri + rj) {
        for (int q = 0; q < 3; q++) pl->xi[q][k] = pl->mr[q][k] = d->pf[q][k] = d->pti[q][k] = d->ptj[q][k] = 0.0;
        return;
    }
    in.n[0] = dx / r;
    in.n[1] = dy / r;
    in.n[2] = dz / r;
    in.overlap = ri + rj - r;
    in.distance = r;
    const double ci = ri - 0.5 * in.overlap, cj = rj - 0.5 * in.overlap;
    const double *wi = d->w + 3 * i, *wj = d->w + 3 * j;
    double sw[3];
    for (int q = 0; q < 3; q++) sw[q] = ci * wi[q] + cj * wj[q];
    in.vc[0] = d->v[3 * i] - d->v[3 * j] - (sw[1] * in.n[2] - sw[2] * in.n[1]);
    in.vc[1] = d->v[3 * i + 1] - d->v[3 * j + 1] - (sw[2] * in.n[0] - sw[0] * in.n[2]);
    in.vc[2] = d->v[3 * i + 2] - d->v[3 * j + 2] - (sw[0] * in.n[1] - sw[1] * in.n[0]);
    for (int q = 0; q < 3; q++) in.wrel[q] = wi[q] - wj[q];
    in.r_eff = ri * rj / (ri + rj);
    in.m_eff = 1.0 / (d->inv_mass[i] + d->inv_mass[j]);
    in.radius_i = ri;
    in.radius_j = rj;
    in.inv_mass_i = d->inv_mass[i];
    in.inv_mass_j = d->inv_mass[j];
    for (int q = 0; q < 3; q++) {
        xi[q] = pl->xi[q][k];
        mr[q] = pl->mr[q][k];
    }
    contact_law(pp, &in, a->dt, xi, mr, &o);
    for (int q = 0; q < 3; q++) {
        pl->xi[q][k] = xi[q];
        pl->mr[q][k] = mr[q];
        d->pf[q][k] = o.force[q];
        d->pti[q][k] = -ci * o.cross[q] + o.mr[q];
        d->ptj[q][k] = -cj * o.cross[q] - o.mr[q];
    }
}

/* Cold path: name the contact of row particle i whose overlap exceeds the limit. */
dem_status dem_report_runaway(dem_domain *d, int64_t i)
{
    const pair_list *pl = &d->pairs_cur;
    const wall_list *wl = &d->walls_cur;
    const double ratio = d->def.max_overlap_ratio, ri = d->radius[i];
    const char *why = "(time step too large for the stiffness and speeds, or particles inserted into each other)";
    for (int64_t k = pl->start[i]; k < pl->start[i + 1]; k++) {
        int32_t j = pl->j[k];
        double r2 = 0;
        for (int a = 0; a < 3; a++) {
            double u = d->x[3 * i + a] - d->x[3 * j + a] - image_sign[pl->image[k]][a] * (d->def.hi[a] - d->def.lo[a]);
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

/* Plane-wall contacts of particle i, added to f/t (after its pair slots). */
void dem_wall_contacts(dem_domain *d, int64_t i, double dt_hist, double *f, double *t, int64_t *bad)
{
    const wall_list *wl = &d->walls_cur;
    const double *xi_ = d->x + 3 * i, *vi = d->v + 3 * i, *wi = d->w + 3 * i;
    const double ri = d->radius[i];
    const pair_props *row_pairs = d->pairs + (size_t)d->mat[i] * d->n_materials;
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
        contact_law(&row_pairs[pw->def.material], &c, dt_hist, hxi, hmr, &o);
        for (int a = 0; a < 3; a++) {
            f[a] += o.force[a];
            t[a] += -ci * o.cross[a] + o.mr[a];
            wf[a] = o.force[a];
        }
    }
}

dem_status dem_forces_compute(dem_domain *d, double dt_hist)
{
    pair_list *pl = &d->pairs_cur;
    kernel_args a;
    a.x = d->x;
    a.v = d->v;
    a.w = d->w;
    a.rad = d->radius;
    a.im = d->inv_mass;
    a.mat = d->mat;
    a.row = pl->row;
    a.jj = pl->j;
    a.image = pl->image;
    for (int q = 0; q < 3; q++) {
        a.xi[q] = pl->xi[q];
        a.mr[q] = pl->mr[q];
        a.pf[q] = d->pf[q];
        a.pti[q] = d->pti[q];
        a.ptj[q] = d->ptj[q];
    }
    for (int s = 0; s < 27; s++) {
        a.sx[s] = image_sign[s][0] * (d->def.hi[0] - d->def.lo[0]);
        a.sy[s] = image_sign[s][1] * (d->def.hi[1] - d->def.lo[1]);
        a.sz[s] = image_sign[s][2] * (d->def.hi[2] - d->def.lo[2]);
    }
    a.dt = dt_hist;
    a.ratio = d->def.max_overlap_ratio;
    /* one material pair everywhere and the kernel covers it: the common, fast case.
     * Otherwise every entry runs the general law (still exact, slower). */
    const int nm = d->n_materials;
    int uniform = 1;
    for (int64_t i = 1; i < d->n && uniform; i++) uniform = d->mat[i] == d->mat[0];
    const pair_props *pp = d->n ? &d->pairs[(size_t)d->mat[0] * nm + d->mat[0]] : d->pairs;
    uniform = uniform && pp->fast;
    a.pp = pp;
    const int rolling = pp->def.rolling_friction > 0.0;
    const int64_t count = pl->count;
    int bad = 0;
#pragma omp parallel for schedule(static) num_threads(d->def.num_threads) reduction(| : bad)
    for (int64_t c0 = 0; c0 < count; c0 += 512) {
        const int64_t c1 = c0 + 512 < count ? c0 + 512 : count;
        if (uniform) {
            bad |= rolling ? pair_kernel_rolling(&a, c0, c1) : pair_kernel_sliding(&a, c0, c1);
        } else {
            for (int64_t k = c0; k < c1; k++)
                general_pair(d, &a, k, &d->pairs[(size_t)d->mat[pl->row[k]] * nm + d->mat[pl->j[k]]]);
        }
    }
    if (bad || !uniform) { /* cold path: the first row particle with a runaway overlap */
        for (int64_t k = 0; k < count; k++) {
            const int64_t i = pl->row[k], j = pl->j[k];
            const int img = pl->image[k];
            const double dx = d->x[3 * i] - (d->x[3 * j] + a.sx[img]);
            const double dy = d->x[3 * i + 1] - (d->x[3 * j + 1] + a.sy[img]);
            const double dz = d->x[3 * i + 2] - (d->x[3 * j + 2] + a.sz[img]);
            const double ri = d->radius[i], rj = d->radius[j];
            if (ri + rj - sqrt(dx * dx + dy * dy + dz * dz) > a.ratio * (ri < rj ? ri : rj))
                return dem_report_runaway(d, i);
        }
    }
    return DEM_OK;
}
