/* The contact law (seed 000 eqs. 3-7): Hertz normal spring + restitution damping,
 * Mindlin tangential spring with history and Coulomb cap, rolling resistance, then the
 * optional effects. One inline kernel shared by particle–particle and particle–wall
 * contacts (and, later, mesh triangles), so every contact feels the same physics. */
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

/* Geometry and kinematics of one contact, seen from particle i. */
typedef struct contact_in {
    double n[3];      /* unit normal from partner to i */
    double overlap;   /* > 0 */
    double distance;  /* centre distance (pair) or centre-to-surface distance (wall) */
    double vc[3];     /* velocity of i relative to partner at the contact point */
    double wrel[3];   /* angular velocity of i minus partner's */
    double r_eff;     /* R* */
    double m_eff;     /* m* */
    double radius_i, radius_j; /* radius_j = 0 for a wall */
    double inv_mass_i, inv_mass_j; /* inv_mass_j = 0 for a wall */
} contact_in;

typedef struct contact_out {
    double force[3];  /* on i */
    double cross[3];  /* n x F_t: torque on body k is -(R_k - overlap/2) * cross */
    double mr[3];     /* rolling torque on i (partner gets -mr) */
} contact_out;

/* The torques a pair contact puts on i and on its partner j (lever arms ci, cj). */
DEM_INLINE void contact_torques(const contact_out *o, double ci, double cj, double *ti, double *tj)
{
    for (int a = 0; a < 3; a++) {
        ti[a] = -ci * o->cross[a] + o->mr[a];
        tj[a] = -cj * o->cross[a] - o->mr[a];
    }
}

DEM_INLINE void vec_project_keep_length(double *h, const double *n)
{
    /* Rotate a history vector into the current tangent plane: project, restore length.
     * The guard on p2 makes h = 0 (a new contact) come out as 0 without a branch. */
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

/* A sphere (radius r, inverse mass im, velocity v, angular velocity w) against a wall surface
 * that moves at vw and turns at ww: the contact for the unit normal n (towards the sphere) at
 * centre-to-surface distance dist. Returns the sphere's lever arm r - overlap/2. */
DEM_INLINE double wall_contact_in(contact_in *c, const double *n, double dist, double r, double im, const double *v,
                                  const double *w, const double *vw, const double *ww)
{
    for (int a = 0; a < 3; a++) c->n[a] = n[a];
    c->overlap = r - dist;
    c->distance = dist;
    const double ci = r - 0.5 * c->overlap;
    c->vc[0] = v[0] - vw[0] - ci * (w[1] * n[2] - w[2] * n[1]);
    c->vc[1] = v[1] - vw[1] - ci * (w[2] * n[0] - w[0] * n[2]);
    c->vc[2] = v[2] - vw[2] - ci * (w[0] * n[1] - w[1] * n[0]);
    for (int a = 0; a < 3; a++) c->wrel[a] = w[a] - ww[a];
    c->r_eff = r;
    c->m_eff = 1.0 / im;
    c->radius_i = r;
    c->radius_j = 0.0;
    c->inv_mass_i = im;
    c->inv_mass_j = 0.0;
    return ci;
}

/* xi: tangential spring (3), mr_hist: rolling torque history (3), both updated in place. */
DEM_INLINE void contact_law(const pair_props *pp, const contact_in *c, double dt, double *xi,
                               double *mr_hist, contact_out *out)
{
    const double *n = c->n;
    const double delta = c->overlap;
    const double sqrt_rd = sqrt(c->r_eff * delta);
    const double sn = 2.0 * pp->e_star * sqrt_rd;
    const double kn = (2.0 / 3.0) * sn;                    /* (4/3) E* sqrt(R* d) */
    const double kt = 8.0 * pp->g_star * sqrt_rd;          /* k_t = S_t = 8 G* sqrt(R* d) */
    const double gn = pp->damping_factor * sqrt(sn * c->m_eff);
    const double gt = gn * pp->st_over_sn_sqrt;

    const double vn = c->vc[0] * n[0] + c->vc[1] * n[1] + c->vc[2] * n[2]; /* > 0: separating */
    double fn = kn * delta - gn * vn;
    if (fn < 0.0) fn = 0.0; /* no attraction from the damper */

    /* tangential */
    double vt[3] = {c->vc[0] - vn * n[0], c->vc[1] - vn * n[1], c->vc[2] - vn * n[2]};
    vec_project_keep_length(xi, n);
    xi[0] += vt[0] * dt;
    xi[1] += vt[1] * dt;
    xi[2] += vt[2] * dt;
    double ft[3] = {-kt * xi[0] - gt * vt[0], -kt * xi[1] - gt * vt[1], -kt * xi[2] - gt * vt[2]};
    const double ft2 = ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2];
    const double ftmax = pp->def.friction * fn;
    if (ft2 > ftmax * ftmax) {
        const double s = ftmax / sqrt(ft2);
        ft[0] *= s;
        ft[1] *= s;
        ft[2] *= s;
        /* Sliding: the spring alone carries the capped force (-kt xi = ft), the dashpot acts in
         * stick only. Resetting xi so that -kt xi - gt vt = ft instead leaves the spring pointing
         * along the slip whenever the dashpot alone exceeds mu F_n (damped impacts), and as kt
         * grows the next steps' friction then pushes along the slip (docs/libdem.md). */
        if (kt > 0.0) {
            const double ik = -1.0 / kt;
            xi[0] = ft[0] * ik;
            xi[1] = ft[1] * ik;
            xi[2] = ft[2] * ik;
        }
    }

    /* rolling resistance */
    out->mr[0] = out->mr[1] = out->mr[2] = 0.0;
    const double mu_r = pp->def.rolling_friction;
    if (mu_r > 0.0) {
        const double *w = c->wrel;
        const double wn = w[0] * n[0] + w[1] * n[1] + w[2] * n[2];
        const double wr[3] = {w[0] - wn * n[0], w[1] - wn * n[1], w[2] - wn * n[2]};
        const double mmax = mu_r * c->r_eff * fn;
        if (pp->def.rolling_model == DEM_ROLLING_CDT) {
            const double wr2 = wr[0] * wr[0] + wr[1] * wr[1] + wr[2] * wr[2];
            if (wr2 > 0.0) {
                const double s = -mmax / sqrt(wr2);
                out->mr[0] = s * wr[0];
                out->mr[1] = s * wr[1];
                out->mr[2] = s * wr[2];
            }
        } else {
            const double kr = (pp->def.rolling_model == DEM_ROLLING_EPSD2)
                                  ? kt * c->r_eff * c->r_eff
                                  : 2.25 * kn * mu_r * mu_r * c->r_eff * c->r_eff;
            vec_project_keep_length(mr_hist, n);
            mr_hist[0] -= kr * wr[0] * dt;
            mr_hist[1] -= kr * wr[1] * dt;
            mr_hist[2] -= kr * wr[2] * dt;
            const double m2 = mr_hist[0] * mr_hist[0] + mr_hist[1] * mr_hist[1] + mr_hist[2] * mr_hist[2];
            int at_limit = 0;
            if (m2 > mmax * mmax) {
                const double s = mmax / sqrt(m2);
                mr_hist[0] *= s;
                mr_hist[1] *= s;
                mr_hist[2] *= s;
                at_limit = 1;
            }
            out->mr[0] = mr_hist[0];
            out->mr[1] = mr_hist[1];
            out->mr[2] = mr_hist[2];
            if (pp->def.rolling_model == DEM_ROLLING_EPSD && pp->def.rolling_damping > 0.0 && !at_limit) {
                /* dashpot: fraction of critical 2 sqrt(I_r k_r), 1/I_r = sum 1/(I_k + m_k r_k^2) (Ai et al.) */
                double inv_ir = c->inv_mass_i / (1.4 * c->radius_i * c->radius_i);
                if (c->radius_j > 0.0) inv_ir += c->inv_mass_j / (1.4 * c->radius_j * c->radius_j);
                const double cr = pp->def.rolling_damping * 2.0 * sqrt(kr / inv_ir);
                out->mr[0] -= cr * wr[0];
                out->mr[1] -= cr * wr[1];
                out->mr[2] -= cr * wr[2];
            }
        }
    }

    /* optional effects add to the normal force (cohesion pulls: negative) and to the torque */
    double fn_total = fn;
    if (pp->n_effects > 0) {
        dem_effect_contact ec;
        for (int a = 0; a < 3; a++) {
            ec.n[a] = n[a];
            ec.wrel[a] = c->wrel[a];
        }
        ec.overlap = delta;
        ec.distance = c->distance;
        ec.radius_i = c->radius_i;
        ec.radius_j = c->radius_j;
        ec.normal_force = fn;
        ec.r_eff = c->r_eff;
        ec.inv_inertia = 2.5 * c->inv_mass_i / (c->radius_i * c->radius_i)
                         + (c->radius_j > 0.0 ? 2.5 * c->inv_mass_j / (c->radius_j * c->radius_j) : 0.0);
        ec.tangential_stiffness = kt;
        for (int k = 0; k < pp->n_effects; k++) {
            const dem_effect_desc *ed = dem_effect_get(pp->effects[k].effect);
            if (ed->normal_force) fn_total += ed->normal_force(&ec, pp->effects[k].params);
            if (ed->torque) ed->torque(&ec, pp->effects[k].params, out->mr);
        }
    }

    out->force[0] = fn_total * n[0] + ft[0];
    out->force[1] = fn_total * n[1] + ft[1];
    out->force[2] = fn_total * n[2] + ft[2];
    out->cross[0] = n[1] * ft[2] - n[2] * ft[1];
    out->cross[1] = n[2] * ft[0] - n[0] * ft[2];
    out->cross[2] = n[0] * ft[1] - n[1] * ft[0];
}

#endif
