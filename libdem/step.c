/* Time stepping: velocity Verlet (kick-drift, forces, kick), neighbour-list refresh when
 * a particle has moved half the skin, failure detection that names the particle, and the
 * time-step checks (Rayleigh time). */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"
#include <float.h>
#include <math.h>
#include <time.h>

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double dem_rayleigh_time(dem_domain *d)
{
    if (d->rayleigh_cache >= 0.0) return d->rayleigh_cache;
    double tmin = INFINITY;
    for (int64_t i = 0; i < d->n; i++) {
        const dem_material_def *m = &d->materials[d->mat[i]];
        double g = dem_material_shear_modulus(m);
        double t = DEM_PI * d->radius[i] * sqrt(m->density / g) / (0.1631 * m->poisson_ratio + 0.8766);
        if (t < tmin) tmin = t;
    }
    d->rayleigh_cache = tmin;
    return tmin;
}

/* Duration of a head-on Hertz impact at speed v (elastic): 2.94328 d_max / v. */
static double hertz_time(double e_star, double r_eff, double m_eff, double v)
{
    double dmax = pow(15.0 * m_eff * v * v / (16.0 * e_star * sqrt(r_eff)), 0.4);
    return 2.94328 * dmax / v;
}

dem_status dem_domain_timestep_info(dem_domain *d, dem_timestep_info *info)
{
    if (!d) return DEM_ERR_NULL;
    if (!info) return dem_fail(d, DEM_ERR_NULL, "dem_domain_timestep_info: info must not be NULL");
    if (d->n == 0) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_domain_timestep_info: no particles yet");
    const int nm = d->n_materials;
    /* smallest particle per material */
    double rmin[64];
    int nmm = nm < 64 ? nm : 64;
    for (int a = 0; a < nmm; a++) rmin[a] = INFINITY;
    for (int64_t i = 0; i < d->n; i++)
        if (d->mat[i] < nmm && d->radius[i] < rmin[d->mat[i]]) rmin[d->mat[i]] = d->radius[i];
    const double v = d->def.reference_velocity;
    double tc = INFINITY;
    for (int a = 0; a < nmm; a++) {
        if (!isfinite(rmin[a])) continue;
        double ma = d->materials[a].density * 4.0 / 3.0 * DEM_PI * pow(rmin[a], 3);
        for (int b = a; b < nmm; b++) {
            if (!isfinite(rmin[b])) continue;
            double mb = d->materials[b].density * 4.0 / 3.0 * DEM_PI * pow(rmin[b], 3);
            double t = hertz_time(dem_pair_props(d, a, b)->e_star, rmin[a] * rmin[b] / (rmin[a] + rmin[b]),
                                  ma * mb / (ma + mb), v);
            if (t < tc) tc = t;
        }
        for (int w = 0; w < d->n_walls + d->n_meshes; w++) {
            int wm = w < d->n_walls ? d->walls[w].def.material.index : d->meshes[w - d->n_walls].material;
            double t = hertz_time(dem_pair_props(d, a, wm)->e_star, rmin[a], ma, v);
            if (t < tc) tc = t;
        }
    }
    info->rayleigh_time = dem_rayleigh_time(d);
    info->hertz_contact_time = tc;
    info->suggested_dt = fmin(0.1 * info->rayleigh_time, tc / 50.0);
    dem_clear_error(d);
    return DEM_OK;
}

/* Make f/t complete for the current state (after insertion, removal, velocity changes):
 * forces with no spring increment. */
static dem_status refresh_forces(dem_domain *d)
{
    if (d->need_rebuild) {
        dem_status s = dem_neighbor_rebuild(d, NULL);
        if (s != DEM_OK) return s;
    }
    sweep_result r = dem_sweep(d, 0.0, SWEEP_FORCES);
    if (r.bad_pair != INT64_MAX) return dem_report_runaway_pair(d, r.bad_pair);
    if (r.bad_wall != INT64_MAX) return dem_report_runaway_wall(d, r.bad_wall);
    dem_meshes_update_servos(d);
    d->forces_valid = 1;
    return DEM_OK;
}

/* The opening half kick and drift of the first step of a call (later steps open inside the
 * sweep that closes the previous one). */
static sweep_result open_first_step(dem_domain *d)
{
    sweep_view view;
    dem_sweep_view(d, &view);
    const int64_t n = d->n;
    double maxdisp2 = 0.0;
    int64_t bad_nan = INT64_MAX, bad_out = INT64_MAX;
#pragma omp parallel for schedule(static) num_threads(dem_team(d)) reduction(max : maxdisp2) \
    reduction(min : bad_nan, bad_out)
    for (int64_t i = 0; i < n; i++) {
        sweep_result res;
        dem_sweep_result_init(&res);
        double *v = d->v + 3 * i, *w = d->w + 3 * i;
        double vl[3] = {v[0], v[1], v[2]}, wl[3] = {w[0], w[1], w[2]};
        dem_open_step(&view, i, d->f + 3 * i, d->t + 3 * i, vl, wl, &res);
        for (int a = 0; a < 3; a++) {
            v[a] = vl[a];
            w[a] = wl[a];
        }
        if (res.maxdisp2 > maxdisp2) maxdisp2 = res.maxdisp2;
        if (res.bad_nan < bad_nan) bad_nan = res.bad_nan;
        if (res.bad_out < bad_out) bad_out = res.bad_out;
    }
    sweep_result m = {maxdisp2, bad_nan, bad_out, INT64_MAX, INT64_MAX};
    return m;
}

dem_status dem_domain_step(dem_domain *d, int64_t n_steps)
{
    if (!d) return DEM_ERR_NULL;
    if (n_steps < 0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_domain_step: n_steps must be >= 0, got %lld", (long long)n_steps);
    const double dt = d->def.dt;
    dem_status result = DEM_OK;
    dem_clear_error(d);
    if (d->n == 0) { /* nothing to collide: time passes, walls move */
        d->tris_cur.count = 0;
        for (int64_t s = 0; s < n_steps; s++) {
            dem_meshes_update_servos(d);
            dem_walls_accumulate_mean_force(d, dt);
            dem_meshes_move(d, dt);
            d->step++;
            d->time += dt;
        }
        d->need_rebuild = 1;
        return DEM_OK;
    }
    const double tr = dem_rayleigh_time(d);
    if (dt > tr)
        return dem_fail(d, DEM_ERR_UNSTABLE_TIMESTEP,
                        "dem_domain_step: dt = %g s exceeds the Rayleigh time %g s; the explicit scheme is unstable "
                        "(use <= %g s)",
                        dt, tr, 0.2 * tr);
    if (dt > 0.2 * tr) {
        dem_fail(d, DEM_WARN_TIMESTEP_LARGE, "dt = %g s is %.0f %% of the Rayleigh time %g s (recommended <= 20 %%)", dt,
                 100.0 * dt / tr, tr);
        result = DEM_WARN_TIMESTEP_LARGE;
    }
    if (!dem_mesh_scratch_reserve(d))
        return dem_fail(d, DEM_ERR_NO_MEMORY, "dem_domain_step: out of memory (mesh contact batches)");
    if (d->need_rebuild || !d->forces_valid) {
        double t0 = now_s();
        dem_status s = refresh_forces(d);
        d->profile.neighbor_s += now_s() - t0;
        if (s != DEM_OK) return s;
    }
    if (n_steps == 0) return result; /* forces of the current state are now valid */

    const double skin_half2 = 0.25 * d->def.skin * d->def.skin;
    double t0 = now_s();
    sweep_result m = open_first_step(d);
    dem_meshes_move(d, dt); /* walls drift with the particles */
    d->profile.integrate_s += now_s() - t0;
    for (int64_t s = 0; s < n_steps; s++) {
        if (m.bad_nan != INT64_MAX) {
            d->forces_valid = 0;
            return dem_fail(d, DEM_ERR_NUMERICAL,
                            "step %lld: particle id %lld has a non-finite position or velocity (NaN/inf)",
                            (long long)d->step + 1, (long long)d->id[m.bad_nan]);
        }
        if (m.bad_out != INT64_MAX) {
            const double *p = d->x + 3 * m.bad_out;
            d->forces_valid = 0;
            return dem_fail(d, DEM_ERR_OUT_OF_BOUNDS, "step %lld: particle id %lld left the domain at (%g, %g, %g)",
                            (long long)d->step + 1, (long long)d->id[m.bad_out], p[0], p[1], p[2]);
        }
        double t1 = now_s();
        /* pairs need each particle within skin/2 of its build position; particle-triangle
         * candidates need particle + wall displacement within the skin */
        if (m.maxdisp2 > skin_half2 || sqrt(m.maxdisp2) + d->mesh_disp > d->def.skin) {
            dem_status st = dem_neighbor_rebuild(d, NULL);
            if (st != DEM_OK) return st;
        }
        double t2 = now_s();
        d->profile.neighbor_s += t2 - t1;
        /* forces, closing half kick and (but for the last step) the next opening half kick + drift */
        if (dem_team(d) < d->def.num_threads) d->profile.steps_fewer_threads++;
        m = dem_sweep(d, dt, s + 1 < n_steps ? SWEEP_CLOSE_OPEN : SWEEP_CLOSE);
        const double t3 = now_s();
        d->profile.contact_s += t3 - t2;
        dem_governor_record(&d->gov, d->def.num_threads, t3 - t2);
        if (m.bad_pair != INT64_MAX || m.bad_wall != INT64_MAX) {
            d->forces_valid = 0;
            return m.bad_pair != INT64_MAX ? dem_report_runaway_pair(d, m.bad_pair)
                                           : dem_report_runaway_wall(d, m.bad_wall);
        }
        dem_meshes_update_servos(d);
        dem_walls_accumulate_mean_force(d, dt);
        if (s + 1 < n_steps) dem_meshes_move(d, dt);
        d->step++;
        d->time += dt;
        d->profile.steps++;
    }
    d->forces_valid = 1; /* the next call continues exactly where this one stopped */
    return result;
}
