/* The contact law (seed 000 eqs. 3-7), written once as small named pieces that both the scalar
 * law below and the batched law (pair_batch.c: pair, mesh-wall and plane-wall contacts) call:
 *
 *   geometry    pair_geometry() / wall_contact_in(): normal, overlap, lever arms, contact-point
 *               velocity, R*, m*
 *   normal      normal_part(): Hertz spring + restitution damper, no attraction; the
 *               stiffnesses the other pieces need
 *   tangential  tangential_part(): Mindlin spring with history, Coulomb cap; while sliding the
 *               spring alone carries mu F_n against the slip (docs/libdem.md)
 *   rolling     rolling_part(): CDT, EPSD or EPSD2 (each its own piece)
 *   effects     effects_part(): the optional effects (effects.c) add a normal force, a
 *               tangential force and/or a torque
 *   assembly    assemble(): the force on i and the torques on i and on its partner
 *
 * The pieces take scalars and small local arrays, so the compiler inlines them into the batch
 * loops and vectorises there; a piece written once gives the same IEEE operations in the same
 * order on either path, so the two paths agree bit for bit (tests/c/test_batch.c). Branches
 * are written as selects where the batch loops need them branch-free. */
#ifndef DEM_CONTACT_LAW_H
#define DEM_CONTACT_LAW_H

#include "internal.h"
#include <float.h>
#include <math.h>

#if defined(__GNUC__)
#define DEM_INLINE static inline __attribute__((always_inline))
#else
#define DEM_INLINE static inline
#endif

/* The constants of one pair type that the law reads (from pair_props). */
typedef struct law_constants {
    double e_star, g_star, damping, st_ratio; /* E*, G*, damping factor, sqrt(S_t/S_n) */
    double friction, rolling, rolling_damping; /* mu_s, mu_r, EPSD dashpot fraction */
    int rolling_model;                         /* dem_rolling_model */
} law_constants;

DEM_INLINE law_constants law_constants_of(const pair_props *pp)
{
    law_constants k = {pp->e_star, pp->g_star, pp->damping_factor, pp->st_over_sn_sqrt, pp->def.friction,
                       pp->def.rolling_friction, pp->def.rolling_damping, (int)pp->def.rolling_model};
    return k;
}

/* Geometry and kinematics of one contact, seen from particle i. */
typedef struct contact_in {
    double n[3];      /* unit normal from partner to i */
    double overlap;   /* > 0 */
    double distance;  /* centre distance (pair) or centre-to-surface distance (wall) */
    double vc[3];     /* velocity of i relative to partner at the contact point */
    double wrel[3];   /* angular velocity of i minus partner's */
    double r_eff;     /* R* */
    double m_eff;     /* m* */
    double ci, cj;    /* lever arms R - overlap/2 (cj = 0 for a wall) */
    double radius_i, radius_j; /* radius_j = 0 for a wall */
    double inv_mass_i, inv_mass_j; /* inv_mass_j = 0 for a wall */
} contact_in;

typedef struct contact_out {
    double force[3];  /* on i */
    double cross[3];  /* n x F_t: torque on body k is -(R_k - overlap/2) * cross */
    double mr[3];     /* rolling torque on i (partner gets -mr) */
} contact_out;

/* ---- geometry ------------------------------------------------------------------------- */

/* A pair contact from d = x_i - x_j (r2 = |d|^2), the radii and inverse masses, the velocity
 * difference dv = v_i - v_j and both angular velocities. */
DEM_INLINE void pair_geometry(contact_in *c, double dx, double dy, double dz, double r2, double ri, double rj,
                              double imi, double imj, const double *dv, const double *wi, const double *wj)
{
    const double r = sqrt(r2), inv_r = 1.0 / r, rsum = ri + rj;
    c->n[0] = dx * inv_r;
    c->n[1] = dy * inv_r;
    c->n[2] = dz * inv_r;
    c->overlap = rsum - r;
    c->distance = r;
    c->ci = ri - 0.5 * c->overlap;
    c->cj = rj - 0.5 * c->overlap;
    const double sw0 = c->ci * wi[0] + c->cj * wj[0], sw1 = c->ci * wi[1] + c->cj * wj[1],
                 sw2 = c->ci * wi[2] + c->cj * wj[2];
    c->vc[0] = dv[0] - (sw1 * c->n[2] - sw2 * c->n[1]);
    c->vc[1] = dv[1] - (sw2 * c->n[0] - sw0 * c->n[2]);
    c->vc[2] = dv[2] - (sw0 * c->n[1] - sw1 * c->n[0]);
    for (int a = 0; a < 3; a++) c->wrel[a] = wi[a] - wj[a];
    c->r_eff = ri * rj / rsum;
    c->m_eff = 1.0 / (imi + imj);
    c->radius_i = ri;
    c->radius_j = rj;
    c->inv_mass_i = imi;
    c->inv_mass_j = imj;
}

/* A sphere (radius r, inverse mass im, angular velocity w) against a wall surface that turns
 * at ww: the contact for the unit normal n (towards the sphere) at centre-to-surface distance
 * dist; dv: the sphere's velocity minus the surface's at the contact. Returns the lever arm. */
DEM_INLINE double wall_geometry(contact_in *c, const double *n, double dist, double r, double im, const double *dv,
                                const double *w, const double *ww)
{
    for (int a = 0; a < 3; a++) c->n[a] = n[a];
    c->overlap = r - dist;
    c->distance = dist;
    const double ci = r - 0.5 * c->overlap;
    c->ci = ci;
    c->cj = 0.0;
    c->vc[0] = dv[0] - ci * (w[1] * n[2] - w[2] * n[1]);
    c->vc[1] = dv[1] - ci * (w[2] * n[0] - w[0] * n[2]);
    c->vc[2] = dv[2] - ci * (w[0] * n[1] - w[1] * n[0]);
    for (int a = 0; a < 3; a++) c->wrel[a] = w[a] - ww[a];
    c->r_eff = r;
    c->m_eff = 1.0 / im;
    c->radius_i = r;
    c->radius_j = 0.0;
    c->inv_mass_i = im;
    c->inv_mass_j = 0.0;
    return ci;
}

/* The same with the sphere's velocity v and the surface's vw apart. */
DEM_INLINE double wall_contact_in(contact_in *c, const double *n, double dist, double r, double im, const double *v,
                                  const double *w, const double *vw, const double *ww)
{
    const double dv[3] = {v[0] - vw[0], v[1] - vw[1], v[2] - vw[2]};
    return wall_geometry(c, n, dist, r, im, dv, w, ww);
}

/* ---- normal --------------------------------------------------------------------------- */

typedef struct normal_out {
    double fn;     /* normal force (>= 0: the damper does not attract) */
    double vn;     /* normal velocity, > 0 separating */
    double kn, kt; /* Hertz normal stiffness (4/3) E* sqrt(R* d), Mindlin k_t = 8 G* sqrt(R* d) */
    double gt;     /* tangential damping coefficient */
} normal_out;

DEM_INLINE normal_out normal_part(const law_constants *k, const contact_in *c)
{
    normal_out o;
    const double sqrt_rd = sqrt(c->r_eff * c->overlap);
    const double sn = 2.0 * k->e_star * sqrt_rd;
    o.kn = (2.0 / 3.0) * sn;
    const double gn = k->damping * sqrt(sn * c->m_eff);
    o.vn = c->vc[0] * c->n[0] + c->vc[1] * c->n[1] + c->vc[2] * c->n[2];
    const double fn = o.kn * c->overlap - gn * o.vn;
    o.fn = fn < 0.0 ? 0.0 : fn;
    o.kt = 8.0 * k->g_star * sqrt_rd;
    o.gt = gn * k->st_ratio;
    return o;
}

/* ---- tangential ------------------------------------------------------------------------ */

/* Rotate a history vector into the current tangent plane: project, restore length. The guard
 * on p2 makes h = 0 (a new contact) come out as 0 without a branch. */
DEM_INLINE void keep_in_plane(double *h, const double *n)
{
    const double h2 = h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
    const double hn = h[0] * n[0] + h[1] * n[1] + h[2] * n[2];
    h[0] -= hn * n[0];
    h[1] -= hn * n[1];
    h[2] -= hn * n[2];
    const double p2 = h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
    const double s = sqrt(h2 / (p2 > DBL_MIN ? p2 : DBL_MIN));
    h[0] *= s;
    h[1] *= s;
    h[2] *= s;
}

/* The tangential velocity vt = vc - vn n. */
DEM_INLINE void tangential_velocity(const contact_in *c, double vn, double *vt)
{
    for (int a = 0; a < 3; a++) vt[a] = c->vc[a] - vn * c->n[a];
}

/* The Mindlin spring xi (updated in place) and dashpot, capped at ftmax = mu F_n: the force ft.
 * Sliding: the spring alone carries the capped force (-kt xi = ft), the dashpot acts in stick
 * only. Resetting xi so that -kt xi - gt vt = ft instead leaves the spring pointing along the
 * slip whenever the dashpot alone exceeds mu F_n (damped impacts), and as kt grows the next
 * steps' friction then pushes along the slip (docs/libdem.md). */
DEM_INLINE void tangential_part(double kt, double gt, double ftmax, const double *n, const double *vt, double dt,
                                double *xi, double *ft)
{
    keep_in_plane(xi, n);
    double x[3], f[3], fc[3];
    for (int a = 0; a < 3; a++) {
        x[a] = xi[a] + vt[a] * dt;
        f[a] = -kt * x[a] - gt * vt[a];
    }
    const double f2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    const int slide = f2 > ftmax * ftmax;
    const double cap = ftmax / sqrt(f2); /* read only when sliding (f2 > 0) */
    const double ik = -1.0 / kt;
    const int reset = slide & (kt > 0.0);
    for (int a = 0; a < 3; a++) {
        fc[a] = f[a] * cap;
        xi[a] = reset ? fc[a] * ik : x[a];
        ft[a] = slide ? fc[a] : f[a];
    }
}

/* ---- rolling ---------------------------------------------------------------------------- */

/* The rolling part of the relative rotation, wr = wrel - (wrel . n) n. */
DEM_INLINE void rolling_velocity(const double *n, const double *w, double *wr)
{
    const double wn = w[0] * n[0] + w[1] * n[1] + w[2] * n[2];
    for (int a = 0; a < 3; a++) wr[a] = w[a] - wn * n[a];
}

/* CDT: the constant torque -mmax wr/|wr| (none while not rolling). */
DEM_INLINE void rolling_cdt(double mmax, const double *wr, int rolls, double *mr)
{
    const double wr2 = wr[0] * wr[0] + wr[1] * wr[1] + wr[2] * wr[2];
    const double s = -mmax / sqrt(wr2);
    const int turn = rolls & (wr2 > 0.0);
    for (int a = 0; a < 3; a++) mr[a] = turn ? s * wr[a] : 0.0;
}

/* The elastic-plastic rolling spring of EPSD and EPSD2 (stiffness kr, limit mmax): the
 * history hist (updated in place where rolls) is the torque; returns whether at the limit. */
DEM_INLINE int rolling_spring(double kr, double mmax, const double *n, const double *wr, double dt, int rolls,
                              double *hist, double *mr)
{
    double y[3] = {hist[0], hist[1], hist[2]};
    keep_in_plane(y, n);
    for (int a = 0; a < 3; a++) y[a] -= kr * wr[a] * dt;
    const double m2 = y[0] * y[0] + y[1] * y[1] + y[2] * y[2];
    const double cap = mmax / sqrt(m2);
    const int limit = m2 > mmax * mmax;
    for (int a = 0; a < 3; a++) {
        y[a] = limit ? y[a] * cap : y[a];
        hist[a] = rolls ? y[a] : hist[a];
        mr[a] = rolls ? y[a] : 0.0;
    }
    return limit;
}

/* What the rolling pieces read of a contact: besides n and wrel, R*, F_n and the stiffnesses,
 * and for EPSD's dashpot the radii and inverse masses (j: 0 for a wall). */
typedef struct rolling_in {
    double r_eff, fn, kn, kt;
    double radius_i, radius_j, inv_mass_i, inv_mass_j;
} rolling_in;

/* Rolling resistance of the given model (a constant where the caller knows it, so the batch
 * loops specialise): the torque mr on i (the partner gets -mr); hist: the spring's history. */
DEM_INLINE void rolling_part(int model, double mu_r, double rolling_damping, const double *n, const double *wrel,
                             const rolling_in *r, double dt, double *hist, double *mr)
{
    double wr[3];
    rolling_velocity(n, wrel, wr);
    const double mmax = mu_r * r->r_eff * r->fn;
    const int rolls = mu_r > 0.0;
    if (model == DEM_ROLLING_CDT) {
        rolling_cdt(mmax, wr, rolls, mr);
        return;
    }
    if (model == DEM_ROLLING_EPSD2) { /* seed 000 eq. 4: k_r = k_t R*^2, no dashpot */
        rolling_spring(r->kt * r->r_eff * r->r_eff, mmax, n, wr, dt, rolls, hist, mr);
        return;
    }
    /* EPSD (Ai et al. 2011): k_r = 2.25 k_n mu_r^2 R*^2 and a dashpot, a fraction of critical
     * 2 sqrt(I_r k_r) with 1/I_r = sum 1/(I_k + m_k r_k^2), acting below the limit */
    const double kr = 2.25 * r->kn * mu_r * mu_r * r->r_eff * r->r_eff;
    const int limit = rolling_spring(kr, mmax, n, wr, dt, rolls, hist, mr);
    if (rolling_damping > 0.0) {
        const double inv_ir_i = r->inv_mass_i / (1.4 * r->radius_i * r->radius_i);
        const double inv_ir = r->radius_j > 0.0 ? inv_ir_i + r->inv_mass_j / (1.4 * r->radius_j * r->radius_j) : inv_ir_i;
        const double cr = rolling_damping * 2.0 * sqrt(kr / inv_ir);
        const int damp = rolls & !limit;
        for (int a = 0; a < 3; a++) mr[a] = damp ? mr[a] - cr * wr[a] : mr[a];
    }
}

/* ---- effects ---------------------------------------------------------------------------- */

/* One effect's kernels on the contact ec: normal force added to *fn_total, tangential force
 * to ft, torque to mr (a descriptor apart from the registry so that tests can drive it). */
DEM_INLINE void effect_apply(const dem_effect_desc *ed, const double *params, const dem_effect_contact *ec,
                             double *fn_total, double *ft, double *mr)
{
    if (ed->normal_force) *fn_total += ed->normal_force(ec, params);
    if (ed->tangential_force) ed->tangential_force(ec, params, ft);
    if (ed->torque) ed->torque(ec, params, mr);
}

/* What an effect's kernels see of a contact (one builder for the scalar law and the batch loops,
 * so both hand the kernels the same numbers): n, wrel, vt as contact_in and tangential_velocity()
 * give them, fn the repulsive normal force, kt the Mindlin stiffness; j's radius and inverse mass
 * 0 for a wall. */
DEM_INLINE void effect_contact_of(dem_effect_contact *ec, const double *n, const double *wrel, const double *vt,
                                  double overlap, double distance, double radius_i, double radius_j, double inv_mass_i,
                                  double inv_mass_j, double r_eff, double fn, double kt)
{
    for (int a = 0; a < 3; a++) {
        ec->n[a] = n[a];
        ec->wrel[a] = wrel[a];
        ec->vt[a] = vt[a];
    }
    ec->overlap = overlap;
    ec->distance = distance;
    ec->radius_i = radius_i;
    ec->radius_j = radius_j;
    ec->normal_force = fn;
    ec->r_eff = r_eff;
    ec->inv_inertia = 2.5 * inv_mass_i / (radius_i * radius_i)
                      + (radius_j > 0.0 ? 2.5 * inv_mass_j / (radius_j * radius_j) : 0.0);
    ec->tangential_stiffness = kt;
}

/* The pair type's effects on the contact ec, in the order they were switched on: their
 * tangential forces added to ft, torques to mr; returns the total normal force. */
DEM_INLINE double effects_add(const pair_props *pp, const dem_effect_contact *ec, double *ft, double *mr)
{
    double fn_total = ec->normal_force;
    for (int k = 0; k < pp->n_effects; k++)
        effect_apply(dem_effect_get(pp->effects[k].effect), pp->effects[k].params, ec, &fn_total, ft, mr);
    return fn_total;
}

/* The same from the scalar law's contact_in and normal_out; returns the total normal force. */
DEM_INLINE double effects_part(const pair_props *pp, const contact_in *c, const normal_out *no, const double *vt,
                               double *ft, double *mr)
{
    if (pp->n_effects == 0) return no->fn;
    dem_effect_contact ec;
    effect_contact_of(&ec, c->n, c->wrel, vt, c->overlap, c->distance, c->radius_i, c->radius_j, c->inv_mass_i,
                      c->inv_mass_j, c->r_eff, no->fn, no->kt);
    return effects_add(pp, &ec, ft, mr);
}

/* ---- assembly --------------------------------------------------------------------------- */

/* The force on i: the normal force along n plus the tangential force. */
DEM_INLINE void contact_force(double fn, const double *n, const double *ft, double *force)
{
    for (int a = 0; a < 3; a++) force[a] = fn * n[a] + ft[a];
}

/* n x ft: the torque on body k is -(R_k - overlap/2) times it. */
DEM_INLINE void tangential_cross(const double *n, const double *ft, double *cross)
{
    cross[0] = n[1] * ft[2] - n[2] * ft[1];
    cross[1] = n[2] * ft[0] - n[0] * ft[2];
    cross[2] = n[0] * ft[1] - n[1] * ft[0];
}

/* The torques a contact puts on i and on its partner (lever arms ci, cj), from n x ft and mr. */
DEM_INLINE void torques_from(const double *cross, const double *mr, double ci, double cj, double *ti, double *tj)
{
    for (int a = 0; a < 3; a++) {
        ti[a] = -ci * cross[a] + mr[a];
        tj[a] = -cj * cross[a] - mr[a];
    }
}

DEM_INLINE void contact_torques(const contact_out *o, double ci, double cj, double *ti, double *tj)
{
    torques_from(o->cross, o->mr, ci, cj, ti, tj);
}

/* ---- the whole law, one contact --------------------------------------------------------- */

/* xi: tangential spring (3), mr_hist: rolling torque history (3), both updated in place. */
DEM_INLINE void contact_law(const pair_props *pp, const contact_in *c, double dt, double *xi, double *mr_hist,
                            contact_out *out)
{
    const law_constants k = law_constants_of(pp);
    const normal_out no = normal_part(&k, c);
    double vt[3], ft[3];
    tangential_velocity(c, no.vn, vt);
    tangential_part(no.kt, no.gt, k.friction * no.fn, c->n, vt, dt, xi, ft);
    out->mr[0] = out->mr[1] = out->mr[2] = 0.0;
    if (k.rolling > 0.0) {
        const rolling_in r = {c->r_eff, no.fn, no.kn, no.kt, c->radius_i, c->radius_j, c->inv_mass_i, c->inv_mass_j};
        rolling_part(k.rolling_model, k.rolling, k.rolling_damping, c->n, c->wrel, &r, dt, mr_hist, out->mr);
    }
    const double fn_total = effects_part(pp, c, &no, vt, ft, out->mr);
    contact_force(fn_total, c->n, ft, out->force);
    tangential_cross(c->n, ft, out->cross);
}

#endif
