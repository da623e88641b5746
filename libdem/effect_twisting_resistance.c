/* Twisting (torsional) resistance: a torque about the contact normal that opposes the relative
 * spin w_n = (w_i - w_j) . n, Coulomb-capped at mu_t R* F_n (the rolling law's cap, with its
 * own coefficient) and viscous below the cap:
 *
 *     M = -sign(w_n) min(mu_t R* F_n, c_t |w_n|) n,   c_t = 2 sqrt(k_tw / (1/I_i + 1/I_j)),
 *
 * k_tw = (2/3) k_t a^2 the torsional stiffness of a Mindlin contact of radius a = sqrt(R* delta)
 * (Deresiewicz: (16/3) G* a^3). A spinning sphere on a plane therefore slows at the constant
 * torque mu_t R F_n and, once |w_n| < cap / c_t, stops within a few contact times (critically
 * damped: no reversal). No history, no time step in the kernel: bitwise restarts stay bitwise.
 * Why: spheres with rolling resistance alone keep spinning about their contact normals, which
 * real angular grains cannot; LIGGGHTS' EPSD2 has the opt-in `torsionTorque` for the same reason.
 * Explicit stability: c_t dt (1/I_i + 1/I_j) = 2 sqrt(k_tw/I) dt, far below 2 at the time steps
 * the Hertz contacts already need (k_tw/I ~ (5/3) (k_t/m) (a/r)^2). */
#include <math.h>

#include "internal.h"

static void twisting_torque(const dem_effect_contact *c, const double *params, double torque[3])
{
    const double mu_t = params[0];
    const double wn = c->wrel[0] * c->n[0] + c->wrel[1] * c->n[1] + c->wrel[2] * c->n[2];
    if (mu_t <= 0.0 || wn == 0.0 || c->inv_inertia <= 0.0) return;
    const double cap = mu_t * c->r_eff * c->normal_force;
    const double k_tw = (2.0 / 3.0) * c->tangential_stiffness * c->r_eff * c->overlap;
    const double c_t = 2.0 * sqrt(k_tw / c->inv_inertia);
    const double m = fmin(cap, c_t * fabs(wn));
    const double s = wn > 0.0 ? -m : m;
    torque[0] += s * c->n[0];
    torque[1] += s * c->n[1];
    torque[2] += s * c->n[2];
}

const dem_effect_desc dem_effect_twisting_resistance = {
    .name = "twisting_resistance",
    .summary = "torque against the relative spin about the contact normal, capped at mu_t R* F_n",
    .n_params = 1,
    .params = {{.name = "twisting_friction", .unit = "", .neutral = 0.0, .min = 0.0, .max = 10.0}},
    .torque = twisting_torque,
};
