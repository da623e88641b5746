/* The batched contact law (see pair_batch.h): the pieces of contact_law.h in stage loops over
 * structure-of-arrays batches, so the compiler vectorises them; tests/c/test_batch.c compares
 * the results with contact_law() bit for bit. */
#include "pair_batch.h"
#include "contact_law.h"
#include <float.h>
#include <math.h>

/* The stage loops write distinct batch slots: tell GCC so it vectorises without run-time
 * overlap checks. */
#if defined(__GNUC__) && !defined(__clang__)
#define DEM_IVDEP _Pragma("GCC ivdep")
#else
#define DEM_IVDEP
#endif

/* Rolling-model cases of the loop besides the dem_rolling_model values: no contact rolls,
 * or the batch mixes models (per contact, not vectorised: several materials with different
 * rolling models in one batch). */
enum { ROLL_NONE = -1, ROLL_MIXED = 3 };

/* The rolling case of a batch of per-contact constants, from the models of the contacts that roll
 * (ROLL_NONE when none does, ROLL_MIXED when they differ): EPSD2 keeps its vectorised loop, a
 * single other model takes the mixed loop (rare). */
static int rolling_case_of(int model)
{
    return model == ROLL_NONE || model == DEM_ROLLING_EPSD2 ? model : ROLL_MIXED;
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
    if (b->uniform) {
        b->has_effects = b->uniform->n_effects > 0;
        b->rolling_case = b->uniform->def.rolling_friction > 0.0 ? (int)b->uniform->def.rolling_model : ROLL_NONE;
        return;
    }
    int any = 0, model = ROLL_NONE;
    for (int q = 0; q < m; q++) {
        const pair_props *pp = b->pp[q];
        b->e_star[q] = pp->e_star;
        b->g_star[q] = pp->g_star;
        b->damping[q] = pp->damping_factor;
        b->st_ratio[q] = pp->st_over_sn_sqrt;
        b->friction[q] = pp->def.friction;
        b->rolling[q] = pp->def.rolling_friction;
        b->rolling_damping[q] = pp->def.rolling_damping;
        b->model[q] = (int8_t)pp->def.rolling_model;
        any |= pp->n_effects > 0;
        if (pp->def.rolling_friction > 0.0) /* the models of the contacts that roll */
            model = model == ROLL_NONE || model == (int)pp->def.rolling_model ? (int)pp->def.rolling_model : ROLL_MIXED;
    }
    b->has_effects = any;
    b->rolling_case = rolling_case_of(model);
}

/* Contact q's constants in a batch with per-contact ones. */
DEM_INLINE law_constants constants_at(const pair_batch *b, int q)
{
    law_constants k = {b->e_star[q], b->g_star[q], b->damping[q], b->st_ratio[q], b->friction[q],
                       b->rolling[q], b->rolling_damping[q], b->model[q]};
    return k;
}

/* The radius of a wall contact's partner, as the effect kernels see it. */
static const double zeros[DEM_PAIR_BATCH];

/* Whether every effect of the pair type is a normal force with a batch kernel (and nothing else). */
static int batch_kernels_only(const pair_props *pp)
{
    for (int k = 0; k < pp->n_effects; k++) {
        const dem_effect_desc *e = dem_effect_get(pp->effects[k].effect);
        if (!e->normal_force_batch || e->tangential_force || e->torque) return 0;
    }
    return 1;
}

/* The loop, specialised (after inlining) for the batch's kind (pair or wall contacts), for a
 * uniform batch, whose constants are `u`, or per-contact constants, for the rolling case
 * `model` (ROLL_NONE drops the rolling stage: 4 of the 15 square roots and divisions per
 * contact) and for whether any contact has effects. Every stage calls the pieces of
 * contact_law.h.
 *
 * Why four loops and not one: a contact's law is one chain of dependent square roots and
 * divisions, longer than the processor's reorder window holds, so in a single loop the next
 * contacts' work cannot start while one contact waits on its chain. Cut into stages that pass
 * their intermediates through the batch's scratch arrays, each stage's chain is short and
 * several contacts run side by side (measured on the law alone without rolling: 1.6 -> 1.8
 * instructions per cycle, -12 % cycles); the operations and their order per contact are
 * unchanged, so the results are too. */
DEM_INLINE void law_loop(pair_batch *b, double dt, const int wall, const int uniform, const int model,
                         const law_constants u, const int effects)
{
    const int m = b->m;
    pair_batch_scratch *s = &b->s;
    /* stage 1: geometry, normal force, stiffnesses, tangential velocity */
    DEM_IVDEP
    for (int q = 0; q < m; q++) {
        contact_in c;
        const double dv[3] = {b->dv[0][q], b->dv[1][q], b->dv[2][q]};
        const double wi[3] = {b->wi[0][q], b->wi[1][q], b->wi[2][q]}, wj[3] = {b->wj[0][q], b->wj[1][q], b->wj[2][q]};
        if (wall) {
            const double n[3] = {b->dx[q], b->dy[q], b->dz[q]};
            wall_geometry(&c, n, b->dist[q], b->ri[q], b->imi[q], dv, wi, wj);
        } else {
            pair_geometry(&c, b->dx[q], b->dy[q], b->dz[q], b->r2[q], b->ri[q], b->rj[q], b->imi[q], b->imj[q], dv, wi,
                          wj);
        }
        const law_constants k = uniform ? u : constants_at(b, q);
        const normal_out no = normal_part(&k, &c);
        double vt[3];
        tangential_velocity(&c, no.vn, vt);
        for (int a = 0; a < 3; a++) {
            s->n[a][q] = c.n[a];
            s->vt[a][q] = vt[a];
        }
        s->ci[q] = c.ci;
        s->cj[q] = c.cj;
        s->r_eff[q] = c.r_eff;
        if (model == DEM_ROLLING_EPSD || model == ROLL_MIXED) s->kn[q] = no.kn; /* EPSD's k_r */
        s->kt[q] = no.kt;
        s->gt[q] = no.gt;
        s->fn[q] = no.fn;
        if (effects) s->distance[q] = c.distance;
        b->overlap[q] = c.overlap;
    }
    /* stage 2: tangential spring and Coulomb cap (the force goes to b->force for now) */
    DEM_IVDEP
    for (int q = 0; q < m; q++) {
        const double n[3] = {s->n[0][q], s->n[1][q], s->n[2][q]}, vt[3] = {s->vt[0][q], s->vt[1][q], s->vt[2][q]};
        double xi[3] = {b->h[0][q], b->h[1][q], b->h[2][q]}, ft[3];
        tangential_part(s->kt[q], s->gt[q], (uniform ? u.friction : b->friction[q]) * s->fn[q], n, vt, dt, xi, ft);
        for (int a = 0; a < 3; a++) {
            b->h[a][q] = xi[a];
            b->force[a][q] = ft[a];
        }
    }
    /* stage 3: rolling resistance (the torque goes to b->ti for now) */
    if (model != ROLL_NONE) {
        DEM_IVDEP
        for (int q = 0; q < m; q++) {
            const double n[3] = {s->n[0][q], s->n[1][q], s->n[2][q]};
            const double wrel[3] = {b->wi[0][q] - b->wj[0][q], b->wi[1][q] - b->wj[1][q], b->wi[2][q] - b->wj[2][q]};
            rolling_in r;
            r.r_eff = s->r_eff[q];
            r.fn = s->fn[q];
            r.kt = s->kt[q];
            if (model == DEM_ROLLING_EPSD || model == ROLL_MIXED) { /* EPSD's stiffness and dashpot */
                r.kn = s->kn[q];
                r.radius_i = b->ri[q];
                r.inv_mass_i = b->imi[q];
                r.radius_j = wall ? 0.0 : b->rj[q];
                r.inv_mass_j = wall ? 0.0 : b->imj[q];
            }
            double hist[3] = {b->h[3][q], b->h[4][q], b->h[5][q]}, mr[3];
            rolling_part(model == ROLL_MIXED ? b->model[q] : model, uniform ? u.rolling : b->rolling[q],
                         uniform ? u.rolling_damping : b->rolling_damping[q], n, wrel, &r, dt, hist, mr);
            for (int a = 0; a < 3; a++) {
                b->h[3 + a][q] = hist[a];
                b->ti[a][q] = mr[a];
            }
        }
    }
    /* stage 3b: the effects (effects.c), after the rolling part as in contact_law(). The total
     * normal force replaces s->fn (the friction and rolling caps above took the repulsive
     * part); torques go to b->ti. Normal-force effects with batch kernels run one vectorised
     * loop each; otherwise the kernels, behind function pointers, run per contact in a loop
     * that is not vectorised — still only they, not the whole scalar law. */
    if (effects && uniform && batch_kernels_only(b->uniform)) {
        /* one pair type whose effects are normal forces with batch kernels (cohesion): each
         * kernel over the whole batch, in the order switched on, adds to the total (each sees
         * the repulsive force in eb.normal_force, as the scalar kernels do), which then
         * replaces s->fn */
        const double *rj = wall ? zeros : b->rj;
        const dem_effect_batch eb = {m, {s->n[0], s->n[1], s->n[2]}, b->overlap, s->distance, b->ri, rj, s->fn,
                                     s->r_eff, s->kt};
        double fn_total[DEM_PAIR_BATCH];
        for (int q = 0; q < m; q++) fn_total[q] = s->fn[q];
        for (int k = 0; k < b->uniform->n_effects; k++) {
            const pair_effect *e = &b->uniform->effects[k];
            dem_effect_get(e->effect)->normal_force_batch(&eb, e->params, fn_total);
        }
        for (int q = 0; q < m; q++) s->fn[q] = fn_total[q];
        if (model == ROLL_NONE)
            for (int a = 0; a < 3; a++)
                for (int q = 0; q < m; q++) b->ti[a][q] = 0.0;
    } else if (effects) {
        for (int q = 0; q < m; q++) {
            const pair_props *pp = uniform ? b->uniform : b->pp[q];
            double mr[3] = {0.0, 0.0, 0.0};
            if (model != ROLL_NONE)
                for (int a = 0; a < 3; a++) mr[a] = b->ti[a][q];
            if (pp->n_effects > 0) {
                const double n[3] = {s->n[0][q], s->n[1][q], s->n[2][q]}, vt[3] = {s->vt[0][q], s->vt[1][q], s->vt[2][q]};
                const double wrel[3] = {b->wi[0][q] - b->wj[0][q], b->wi[1][q] - b->wj[1][q], b->wi[2][q] - b->wj[2][q]};
                double ft[3] = {b->force[0][q], b->force[1][q], b->force[2][q]};
                dem_effect_contact ec;
                effect_contact_of(&ec, n, wrel, vt, b->overlap[q], s->distance[q], b->ri[q], wall ? 0.0 : b->rj[q],
                                  b->imi[q], wall ? 0.0 : b->imj[q], s->r_eff[q], s->fn[q], s->kt[q]);
                s->fn[q] = effects_add(pp, &ec, ft, mr);
                for (int a = 0; a < 3; a++) b->force[a][q] = ft[a];
            }
            for (int a = 0; a < 3; a++) b->ti[a][q] = mr[a];
        }
    }
    /* stage 4: force on i; torques on i and on j */
    DEM_IVDEP
    for (int q = 0; q < m; q++) {
        const double n[3] = {s->n[0][q], s->n[1][q], s->n[2][q]}, fn = s->fn[q];
        const double ft[3] = {b->force[0][q], b->force[1][q], b->force[2][q]};
        double mr[3] = {0.0, 0.0, 0.0}, cross[3], ti[3], tj[3], f[3];
        if (model != ROLL_NONE || effects)
            for (int a = 0; a < 3; a++) mr[a] = b->ti[a][q];
        tangential_cross(n, ft, cross);
        torques_from(cross, mr, s->ci[q], s->cj[q], ti, tj);
        contact_force(fn, n, ft, f);
        for (int a = 0; a < 3; a++) {
            b->force[a][q] = f[a];
            b->ti[a][q] = ti[a];
            b->tj[a][q] = tj[a];
        }
    }
}

/* The loop specialised for the batch's kind, constants, rolling case and effects. */
DEM_INLINE void law_case(pair_batch *b, double dt, const int wall, const int effects)
{
    static const law_constants none = {0, 0, 0, 0, 0, 0, 0, 0};
    if (b->uniform) {
        const law_constants u = law_constants_of(b->uniform);
        switch (b->rolling_case) {
        case ROLL_NONE: law_loop(b, dt, wall, 1, ROLL_NONE, u, effects); break;
        case DEM_ROLLING_CDT: law_loop(b, dt, wall, 1, DEM_ROLLING_CDT, u, effects); break;
        case DEM_ROLLING_EPSD: law_loop(b, dt, wall, 1, DEM_ROLLING_EPSD, u, effects); break;
        default: law_loop(b, dt, wall, 1, DEM_ROLLING_EPSD2, u, effects); break;
        }
        return;
    }
    switch (b->rolling_case) {
    case ROLL_NONE: law_loop(b, dt, wall, 0, ROLL_NONE, none, effects); break;
    case DEM_ROLLING_EPSD2: law_loop(b, dt, wall, 0, DEM_ROLLING_EPSD2, none, effects); break;
    default: law_loop(b, dt, wall, 0, ROLL_MIXED, none, effects); break;
    }
}

DEM_INLINE void law_kind(pair_batch *b, double dt, const int wall)
{
    if (b->has_effects) law_case(b, dt, wall, 1);
    else law_case(b, dt, wall, 0);
}

void dem_pair_batch_law(pair_batch *b, double dt)
{
    law_kind(b, dt, 0);
}

void dem_wall_batch_law(pair_batch *b, double dt)
{
    law_kind(b, dt, 1);
}

void dem_pair_batch_contact_in(const pair_batch *b, int q, contact_in *in)
{
    const double dv[3] = {b->dv[0][q], b->dv[1][q], b->dv[2][q]};
    const double wi[3] = {b->wi[0][q], b->wi[1][q], b->wi[2][q]}, wj[3] = {b->wj[0][q], b->wj[1][q], b->wj[2][q]};
    pair_geometry(in, b->dx[q], b->dy[q], b->dz[q], b->r2[q], b->ri[q], b->rj[q], b->imi[q], b->imj[q], dv, wi, wj);
}
