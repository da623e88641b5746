/* The batched pair contact law (see pair_batch.h): the operations of the pair geometry in
 * sweep.c and of contact_law() in contact_law.h, in their order, written branch-free so the
 * loop vectorises. Keep the three in step: tests/c/test_batch.c compares this loop with
 * contact_law() bit for bit. */
#include "pair_batch.h"
#include "contact_law.h"
#include <float.h>
#include <math.h>
#include <string.h>

/* The stage loops write distinct batch slots: tell GCC so it vectorises without run-time
 * overlap checks. */
#if defined(__GNUC__) && !defined(__clang__)
#define DEM_IVDEP _Pragma("GCC ivdep")
#else
#define DEM_IVDEP
#endif

/* vec_project_keep_length() of contact_law.h on three scalars (so the loop stays vectorisable). */
DEM_INLINE void keep_in_plane(double *x0, double *x1, double *x2, double n0, double n1, double n2)
{
    const double h2 = *x0 * *x0 + *x1 * *x1 + *x2 * *x2;
    const double hn = *x0 * n0 + *x1 * n1 + *x2 * n2;
    *x0 -= hn * n0;
    *x1 -= hn * n1;
    *x2 -= hn * n2;
    const double p2 = *x0 * *x0 + *x1 * *x1 + *x2 * *x2;
    const double s = sqrt(h2 / (p2 > DBL_MIN ? p2 : DBL_MIN));
    *x0 *= s;
    *x1 *= s;
    *x2 *= s;
}

int dem_takes_scalar_law(const pair_props *pp)
{
    return pp->n_effects > 0 || (pp->def.rolling_model != DEM_ROLLING_EPSD2 && pp->def.rolling_friction > 0.0);
}

void dem_pair_batch_props(pair_batch *b, const pair_props *all)
{
    const int m = b->m;
    if (all) {
        b->uniform = all;
    } else {
        int same = 1;
        for (int q = 1; q < m; q++) same &= b->pp[q] == b->pp[0];
        b->uniform = m > 0 && same ? b->pp[0] : NULL;
    }
    if (b->uniform) { /* the flags are read only where any_scalar is set */
        const uint8_t sc = (uint8_t)dem_takes_scalar_law(b->uniform);
        if (sc) memset(b->scalar, 1, (size_t)m);
        b->any_scalar = sc;
        return;
    }
    int any = 0;
    for (int q = 0; q < m; q++) {
        const pair_props *pp = b->pp[q];
        b->e_star[q] = pp->e_star;
        b->g_star[q] = pp->g_star;
        b->damping[q] = pp->damping_factor;
        b->st_ratio[q] = pp->st_over_sn_sqrt;
        b->friction[q] = pp->def.friction;
        b->rolling[q] = pp->def.rolling_model == DEM_ROLLING_EPSD2 ? pp->def.rolling_friction : 0.0;
        b->scalar[q] = (uint8_t)dem_takes_scalar_law(pp);
        any |= b->scalar[q];
    }
    b->any_scalar = any;
}

/* The loop, specialised (after inlining) for a uniform batch, whose constants are the u_*
 * arguments, and for per-contact constants; `no_rolling` (a uniform batch without rolling
 * resistance) drops the rolling spring, whose result would be discarded: 4 of the 15 square
 * roots and divisions per contact.
 *
 * Why four loops and not one: a contact's law is one chain of dependent square roots and
 * divisions, longer than the processor's reorder window holds, so in a single loop the next
 * contacts' work cannot start while one contact waits on its chain. Cut into stages that pass
 * their intermediates through the batch's scratch arrays, each stage's chain is short and
 * several contacts run side by side (measured on the law alone without rolling: 1.6 -> 1.8
 * instructions per cycle, -12 % cycles); the operations and their order per contact are
 * unchanged, so the results are too. */
DEM_INLINE void law_loop(pair_batch *b, double dt, const int wall, const int uniform, const int no_rolling,
                         const double u_e_star, const double u_g_star, const double u_damping, const double u_st_ratio,
                         const double u_friction, const double u_rolling)
{
    const int m = b->m;
    pair_batch_scratch *s = &b->s;
    /* stage 1: geometry (unit normal from j to i, overlap, lever arms, contact-point
     * velocity), stiffnesses, normal force (Hertz spring + restitution damper, no attraction)
     * and tangential velocity. A wall contact's geometry is that of wall_contact_in(). */
    DEM_IVDEP
    for (int q = 0; q < m; q++) {
        double n0, n1, n2, delta, ci, cj, vc0, vc1, vc2, r_eff, m_eff;
        if (wall) {
            n0 = b->dx[q];
            n1 = b->dy[q];
            n2 = b->dz[q];
            const double r = b->ri[q], *w0 = b->wi[0], *w1 = b->wi[1], *w2 = b->wi[2];
            delta = r - b->dist[q];
            ci = r - 0.5 * delta;
            cj = 0.0;
            vc0 = b->dv[0][q] - ci * (w1[q] * n2 - w2[q] * n1);
            vc1 = b->dv[1][q] - ci * (w2[q] * n0 - w0[q] * n2);
            vc2 = b->dv[2][q] - ci * (w0[q] * n1 - w1[q] * n0);
            r_eff = r;
            m_eff = 1.0 / b->imi[q];
        } else {
            const double r = sqrt(b->r2[q]), inv_r = 1.0 / r;
            n0 = b->dx[q] * inv_r;
            n1 = b->dy[q] * inv_r;
            n2 = b->dz[q] * inv_r;
            const double ri = b->ri[q], rj = b->rj[q], rsum = ri + rj;
            delta = rsum - r;
            ci = ri - 0.5 * delta;
            cj = rj - 0.5 * delta;
            const double sw0 = ci * b->wi[0][q] + cj * b->wj[0][q], sw1 = ci * b->wi[1][q] + cj * b->wj[1][q],
                         sw2 = ci * b->wi[2][q] + cj * b->wj[2][q];
            vc0 = b->dv[0][q] - (sw1 * n2 - sw2 * n1);
            vc1 = b->dv[1][q] - (sw2 * n0 - sw0 * n2);
            vc2 = b->dv[2][q] - (sw0 * n1 - sw1 * n0);
            r_eff = ri * rj / rsum;
            m_eff = 1.0 / (b->imi[q] + b->imj[q]);
        }
        const double sqrt_rd = sqrt(r_eff * delta);
        const double sn = 2.0 * (uniform ? u_e_star : b->e_star[q]) * sqrt_rd;
        const double kn = (2.0 / 3.0) * sn;
        const double gn = (uniform ? u_damping : b->damping[q]) * sqrt(sn * m_eff);
        const double vn = vc0 * n0 + vc1 * n1 + vc2 * n2;
        const double fn = kn * delta - gn * vn;
        s->n[0][q] = n0;
        s->n[1][q] = n1;
        s->n[2][q] = n2;
        s->ci[q] = ci;
        s->cj[q] = cj;
        s->r_eff[q] = r_eff;
        s->kt[q] = 8.0 * (uniform ? u_g_star : b->g_star[q]) * sqrt_rd;
        s->gt[q] = gn * (uniform ? u_st_ratio : b->st_ratio[q]);
        s->fn[q] = fn < 0.0 ? 0.0 : fn;
        s->vt[0][q] = vc0 - vn * n0;
        s->vt[1][q] = vc1 - vn * n1;
        s->vt[2][q] = vc2 - vn * n2;
        b->overlap[q] = delta;
    }
    /* stage 2: tangential spring rotated into the tangent plane, Coulomb cap (the force goes
     * to b->force for now) */
    DEM_IVDEP
    for (int q = 0; q < m; q++) {
        const double n0 = s->n[0][q], n1 = s->n[1][q], n2 = s->n[2][q];
        const double vt0 = s->vt[0][q], vt1 = s->vt[1][q], vt2 = s->vt[2][q];
        const double kt = s->kt[q], gt = s->gt[q];
        double x0 = b->h[0][q], x1 = b->h[1][q], x2 = b->h[2][q];
        keep_in_plane(&x0, &x1, &x2, n0, n1, n2);
        x0 += vt0 * dt;
        x1 += vt1 * dt;
        x2 += vt2 * dt;
        double ft0 = -kt * x0 - gt * vt0, ft1 = -kt * x1 - gt * vt1, ft2 = -kt * x2 - gt * vt2;
        const double ft_sq = ft0 * ft0 + ft1 * ft1 + ft2 * ft2;
        const double ftmax = (uniform ? u_friction : b->friction[q]) * s->fn[q];
        const int slide = ft_sq > ftmax * ftmax;
        const double cap = ftmax / sqrt(ft_sq);
        const double fc0 = ft0 * cap, fc1 = ft1 * cap, fc2 = ft2 * cap;
        const double ik = -1.0 / kt;
        const int reset = slide & (kt > 0.0);
        b->h[0][q] = reset ? fc0 * ik : x0;
        b->h[1][q] = reset ? fc1 * ik : x1;
        b->h[2][q] = reset ? fc2 * ik : x2;
        b->force[0][q] = slide ? fc0 : ft0;
        b->force[1][q] = slide ? fc1 : ft1;
        b->force[2][q] = slide ? fc2 : ft2;
    }
    /* stage 3: rolling resistance, EPSD2: elastic-plastic spring kr = kt R*^2, limit
     * mu_r R* F_n (the torque goes to b->ti for now) */
    if (!no_rolling) {
        DEM_IVDEP
        for (int q = 0; q < m; q++) {
            const double n0 = s->n[0][q], n1 = s->n[1][q], n2 = s->n[2][q];
            const double mu_r = uniform ? u_rolling : b->rolling[q];
            const double r_eff = s->r_eff[q];
            const double wr0 = b->wi[0][q] - b->wj[0][q], wr1 = b->wi[1][q] - b->wj[1][q],
                         wr2 = b->wi[2][q] - b->wj[2][q];
            const double wn = wr0 * n0 + wr1 * n1 + wr2 * n2;
            const double u0 = wr0 - wn * n0, u1 = wr1 - wn * n1, u2 = wr2 - wn * n2;
            const double mmax = mu_r * r_eff * s->fn[q];
            const double kr = s->kt[q] * r_eff * r_eff;
            const double y0_in = b->h[3][q], y1_in = b->h[4][q], y2_in = b->h[5][q];
            double y0 = y0_in, y1 = y1_in, y2 = y2_in;
            keep_in_plane(&y0, &y1, &y2, n0, n1, n2);
            y0 -= kr * u0 * dt;
            y1 -= kr * u1 * dt;
            y2 -= kr * u2 * dt;
            const double m2 = y0 * y0 + y1 * y1 + y2 * y2;
            const double mcap = mmax / sqrt(m2);
            const int limit = m2 > mmax * mmax;
            y0 = limit ? y0 * mcap : y0;
            y1 = limit ? y1 * mcap : y1;
            y2 = limit ? y2 * mcap : y2;
            const int rolls = mu_r > 0.0;
            b->h[3][q] = rolls ? y0 : y0_in;
            b->h[4][q] = rolls ? y1 : y1_in;
            b->h[5][q] = rolls ? y2 : y2_in;
            b->ti[0][q] = rolls ? y0 : 0.0;
            b->ti[1][q] = rolls ? y1 : 0.0;
            b->ti[2][q] = rolls ? y2 : 0.0;
        }
    }
    /* stage 4: force on i; torques on i and on j (contact_torques() of contact_law.h) */
    DEM_IVDEP
    for (int q = 0; q < m; q++) {
        const double n0 = s->n[0][q], n1 = s->n[1][q], n2 = s->n[2][q], fn = s->fn[q];
        const double ft0 = b->force[0][q], ft1 = b->force[1][q], ft2 = b->force[2][q];
        const double ci = s->ci[q], cj = s->cj[q];
        const double mr0 = no_rolling ? 0.0 : b->ti[0][q], mr1 = no_rolling ? 0.0 : b->ti[1][q],
                     mr2 = no_rolling ? 0.0 : b->ti[2][q];
        const double cr0 = n1 * ft2 - n2 * ft1, cr1 = n2 * ft0 - n0 * ft2, cr2 = n0 * ft1 - n1 * ft0;
        b->force[0][q] = fn * n0 + ft0;
        b->force[1][q] = fn * n1 + ft1;
        b->force[2][q] = fn * n2 + ft2;
        b->ti[0][q] = -ci * cr0 + mr0;
        b->ti[1][q] = -ci * cr1 + mr1;
        b->ti[2][q] = -ci * cr2 + mr2;
        b->tj[0][q] = -cj * cr0 - mr0;
        b->tj[1][q] = -cj * cr1 - mr1;
        b->tj[2][q] = -cj * cr2 - mr2;
    }
}

/* The loop specialised for the batch's kind (pair or wall contacts) and pair constants. */
DEM_INLINE void law_kind(pair_batch *b, double dt, const int wall)
{
    const pair_props *u = b->uniform;
    const double u_rolling = u && u->def.rolling_model == DEM_ROLLING_EPSD2 ? u->def.rolling_friction : 0.0;
    if (u && u_rolling > 0.0)
        law_loop(b, dt, wall, 1, 0, u->e_star, u->g_star, u->damping_factor, u->st_over_sn_sqrt, u->def.friction,
                 u_rolling);
    else if (u)
        law_loop(b, dt, wall, 1, 1, u->e_star, u->g_star, u->damping_factor, u->st_over_sn_sqrt, u->def.friction, 0.0);
    else
        law_loop(b, dt, wall, 0, 0, 0, 0, 0, 0, 0, 0);
}

void dem_pair_batch_law(pair_batch *b, double dt)
{
    law_kind(b, dt, 0);
}

void dem_wall_batch_law(pair_batch *b, double dt)
{
    law_kind(b, dt, 1);
}

void dem_pair_batch_contact_in(const pair_batch *b, int q, contact_in *in, double *ci, double *cj)
{
    const double r = sqrt(b->r2[q]), inv_r = 1.0 / r;
    const double ri = b->ri[q], rj = b->rj[q], rsum = ri + rj;
    in->n[0] = b->dx[q] * inv_r;
    in->n[1] = b->dy[q] * inv_r;
    in->n[2] = b->dz[q] * inv_r;
    in->overlap = rsum - r;
    in->distance = r;
    *ci = ri - 0.5 * in->overlap;
    *cj = rj - 0.5 * in->overlap;
    double sw[3];
    for (int a = 0; a < 3; a++) sw[a] = *ci * b->wi[a][q] + *cj * b->wj[a][q];
    in->vc[0] = b->dv[0][q] - (sw[1] * in->n[2] - sw[2] * in->n[1]);
    in->vc[1] = b->dv[1][q] - (sw[2] * in->n[0] - sw[0] * in->n[2]);
    in->vc[2] = b->dv[2][q] - (sw[0] * in->n[1] - sw[1] * in->n[0]);
    for (int a = 0; a < 3; a++) in->wrel[a] = b->wi[a][q] - b->wj[a][q];
    in->r_eff = ri * rj / rsum;
    in->m_eff = 1.0 / (b->imi[q] + b->imj[q]);
    in->radius_i = ri;
    in->radius_j = rj;
    in->inv_mass_i = b->imi[q];
    in->inv_mass_j = b->imj[q];
}

void dem_pair_batch_law_scalar(pair_batch *b, double dt, const double *list_hist)
{
    for (int q = 0; q < b->m; q++) {
        if (!b->scalar[q]) continue;
        contact_in in;
        double ci, cj, hist[6];
        dem_pair_batch_contact_in(b, q, &in, &ci, &cj);
        for (int a = 0; a < 6; a++) hist[a] = list_hist[6 * b->k[q] + a]; /* the batch loop moved b->h */
        contact_out o;
        contact_law(b->uniform ? b->uniform : b->pp[q], &in, dt, hist, hist + 3, &o);
        for (int a = 0; a < 6; a++) b->h[a][q] = hist[a];
        double ti[3], tj[3];
        contact_torques(&o, ci, cj, ti, tj);
        for (int a = 0; a < 3; a++) {
            b->force[a][q] = o.force[a];
            b->ti[a][q] = ti[a];
            b->tj[a][q] = tj[a];
        }
        b->overlap[q] = in.overlap;
    }
}
