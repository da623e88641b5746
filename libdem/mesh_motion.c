/* Mesh-wall motion: prescribed translation + rotation about a moving centre, integrated
 * exactly per step (Rodrigues rotation, re-orthonormalised), and the load-control servo. */
#include "internal.h"
#include "triangle.h"
#include <math.h>
#include <string.h>

dem_servo_def dem_default_servo_def(void)
{
    dem_servo_def s;
    memset(&s, 0, sizeof s);
    s.direction[2] = -1.0;
    s.max_speed = 0.05;
    s.proportional_band = 0.2;
    return s;
}

void dem_mesh_update_world(mesh_wall *m)
{
    const double *r = m->rot;
    for (int64_t v = 0; v < m->nv; v++) {
        const double *p = m->x_ref + 3 * v;
        double *x = m->x + 3 * v;
        for (int a = 0; a < 3; a++) x[a] = r[3 * a] * p[0] + r[3 * a + 1] * p[1] + r[3 * a + 2] * p[2] + m->trans[a];
    }
    for (int64_t t = 0; t < m->nt; t++) {
        const double *a = m->x + 3 * m->tri[3 * t], *b = m->x + 3 * m->tri[3 * t + 1], *c = m->x + 3 * m->tri[3 * t + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++) m->normal[3 * t + k] = n[k] / len;
    }
}

/* R <- Rot(axis, angle) R, then Gram-Schmidt on the rows so round-off cannot accumulate. */
static void rotate_pose(mesh_wall *m, const double *w, double dt)
{
    double wl = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (wl == 0.0) return;
    double k[3] = {w[0] / wl, w[1] / wl, w[2] / wl}, th = wl * dt, c = cos(th), s = sin(th), C = 1.0 - c;
    double q[9] = {c + k[0] * k[0] * C,        k[0] * k[1] * C - k[2] * s, k[0] * k[2] * C + k[1] * s,
                   k[1] * k[0] * C + k[2] * s, c + k[1] * k[1] * C,        k[1] * k[2] * C - k[0] * s,
                   k[2] * k[0] * C - k[1] * s, k[2] * k[1] * C + k[0] * s, c + k[2] * k[2] * C};
    double r[9], t[3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) r[3 * i + j] = q[3 * i] * m->rot[j] + q[3 * i + 1] * m->rot[3 + j] + q[3 * i + 2] * m->rot[6 + j];
    /* the translation part rotates about the centre: t' = Q (t - c) + c */
    double u[3] = {m->trans[0] - m->centre[0], m->trans[1] - m->centre[1], m->trans[2] - m->centre[2]};
    for (int i = 0; i < 3; i++) t[i] = q[3 * i] * u[0] + q[3 * i + 1] * u[1] + q[3 * i + 2] * u[2] + m->centre[i];
    for (int i = 0; i < 3; i++) { /* orthonormalise rows */
        double *ri = r + 3 * i;
        for (int j = 0; j < i; j++) {
            const double *rj = r + 3 * j;
            double dp = ri[0] * rj[0] + ri[1] * rj[1] + ri[2] * rj[2];
            for (int a = 0; a < 3; a++) ri[a] -= dp * rj[a];
        }
        double len = sqrt(ri[0] * ri[0] + ri[1] * ri[1] + ri[2] * ri[2]);
        for (int a = 0; a < 3; a++) ri[a] /= len;
    }
    memcpy(m->rot, r, sizeof r);
    memcpy(m->trans, t, sizeof t);
}

void dem_meshes_move(dem_domain *d, double dt)
{
    for (int k = 0; k < d->n_meshes; k++) {
        mesh_wall *m = &d->meshes[k];
        if (!m->moving) continue;
        rotate_pose(m, m->omega, dt);
        for (int a = 0; a < 3; a++) {
            m->trans[a] += m->velocity[a] * dt;
            m->centre[a] += m->velocity[a] * dt;
        }
        dem_mesh_update_world(m);
        dem_mesh_measure_disp(m);
        if (m->disp > d->mesh_disp) d->mesh_disp = m->disp;
    }
}

void dem_mesh_measure_disp(mesh_wall *m)
{
    double maxd2 = 0.0;
    for (int64_t v = 0; v < m->nv; v++) {
        double u2 = tri_dist2(m->x + 3 * v, m->x_build + 3 * v);
        if (u2 > maxd2) maxd2 = u2;
    }
    m->disp = sqrt(maxd2);
}

void dem_meshes_update_servos(dem_domain *d)
{
    for (int k = 0; k < d->n_meshes; k++) {
        mesh_wall *m = &d->meshes[k];
        if (!m->servo_on) continue;
        const dem_servo_def *s = &m->servo;
        double f[3];
        dem_mesh_total_force(d, k, f);
        double load = -(f[0] * s->direction[0] + f[1] * s->direction[1] + f[2] * s->direction[2]);
        if (!m->servo_primed || s->filter_time <= 0.0) {
            m->servo_force = load;
            m->servo_primed = 1;
        } else {
            m->servo_force += d->def.dt / (s->filter_time + d->def.dt) * (load - m->servo_force);
        }
        double target = s->area > 0.0 ? s->target_stress * s->area : s->target_force;
        double e = (target - m->servo_force) / (s->proportional_band * target);
        if (e > 1.0) e = 1.0;
        if (e < -1.0) e = -1.0;
        for (int a = 0; a < 3; a++) m->velocity[a] = s->max_speed * e * s->direction[a];
    }
}

/* ---- API ------------------------------------------------------------------------------ */
static dem_status get_mesh(dem_domain *d, int mesh, const char *fn, mesh_wall **out)
{
    if (mesh < 0 || mesh >= d->n_meshes)
        return dem_fail(d, DEM_ERR_UNKNOWN_WALL, "%s: unknown mesh wall %d (%d exist)", fn, mesh, d->n_meshes);
    *out = &d->meshes[mesh];
    return DEM_OK;
}

static int all_finite(const double *v, int n)
{
    for (int k = 0; k < n; k++)
        if (!dem_is_finite(v[k])) return 0;
    return 1;
}

static void update_moving(mesh_wall *m)
{
    m->moving = m->servo_on;
    for (int a = 0; a < 3; a++) m->moving |= (m->velocity[a] != 0.0) | (m->omega[a] != 0.0);
}

dem_status dem_mesh_wall_set_motion(dem_domain *d, dem_mesh_wall mesh_handle, const double velocity[3], const double angular_velocity[3],
                                    const double centre[3])
{
    const int mesh = mesh_handle.index;
    const char *fn = "dem_mesh_wall_set_motion";
    if (!d) return DEM_ERR_NULL;
    if (!velocity) return dem_fail(d, DEM_ERR_NULL, "%s: velocity must not be NULL", fn);
    mesh_wall *m = NULL;
    dem_status s = get_mesh(d, mesh, fn, &m);
    if (s != DEM_OK) return s;
    if (!all_finite(velocity, 3) || (angular_velocity && !all_finite(angular_velocity, 3)) || (centre && !all_finite(centre, 3)))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: velocity, angular velocity and centre must be finite", fn);
    if (angular_velocity && !centre)
        return dem_fail(d, DEM_ERR_NULL, "%s: a rotation needs its centre (a point on the axis)", fn);
    for (int a = 0; a < 3; a++) {
        m->velocity[a] = velocity[a];
        m->omega[a] = angular_velocity ? angular_velocity[a] : 0.0;
        if (centre) m->centre[a] = centre[a];
    }
    m->servo_on = 0;
    update_moving(m);
    d->forces_valid = 0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_mesh_wall_set_servo(dem_domain *d, dem_mesh_wall mesh_handle, const dem_servo_def *def)
{
    const int mesh = mesh_handle.index;
    const char *fn = "dem_mesh_wall_set_servo";
    if (!d) return DEM_ERR_NULL;
    if (!def) return dem_fail(d, DEM_ERR_NULL, "%s: def must not be NULL", fn);
    mesh_wall *m = NULL;
    dem_status s = get_mesh(d, mesh, fn, &m);
    if (s != DEM_OK) return s;
    double len = sqrt(def->direction[0] * def->direction[0] + def->direction[1] * def->direction[1] +
                      def->direction[2] * def->direction[2]);
    if (!all_finite(def->direction, 3) || fabs(len - 1.0) > 1e-6)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: direction must be a unit vector (length %g)", fn, len);
    if (def->area < 0.0 || !dem_is_finite(def->area))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: area must be finite and >= 0 m^2, got %g", fn, def->area);
    double target = def->area > 0.0 ? def->target_stress * def->area : def->target_force;
    if (!(target > 0.0) || !dem_is_finite(target))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: the target (%s) must be finite and > 0, got %g", fn,
                        def->area > 0.0 ? "target_stress x area" : "target_force", target);
    if (!(def->max_speed > 0.0) || !dem_is_finite(def->max_speed))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: max_speed must be finite and > 0 m/s, got %g", fn, def->max_speed);
    if (!(def->proportional_band > 0.0) || !dem_is_finite(def->proportional_band))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: proportional_band must be finite and > 0, got %g", fn,
                        def->proportional_band);
    if (!(def->filter_time >= 0.0) || !dem_is_finite(def->filter_time))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: filter_time must be finite and >= 0 s, got %g", fn, def->filter_time);
    m->servo = *def;
    m->servo_on = 1;
    m->servo_primed = 0;
    update_moving(m);
    d->forces_valid = 0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_mesh_wall_servo_off(dem_domain *d, dem_mesh_wall mesh_handle)
{
    const int mesh = mesh_handle.index;
    if (!d) return DEM_ERR_NULL;
    mesh_wall *m = NULL;
    dem_status s = get_mesh(d, mesh, "dem_mesh_wall_servo_off", &m);
    if (s != DEM_OK) return s;
    m->servo_on = 0;
    for (int a = 0; a < 3; a++) m->velocity[a] = 0.0;
    update_moving(m);
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_mesh_wall_get_pose(const dem_domain *d, dem_mesh_wall mesh_handle, double translation[3], double rotation[9])
{
    const int mesh = mesh_handle.index;
    if (!d) return DEM_ERR_NULL;
    if (mesh < 0 || mesh >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    if (translation) memcpy(translation, d->meshes[mesh].trans, 3 * sizeof(double));
    if (rotation) memcpy(rotation, d->meshes[mesh].rot, 9 * sizeof(double));
    return DEM_OK;
}

dem_status dem_mesh_wall_get_velocity(const dem_domain *d, dem_mesh_wall mesh_handle, double velocity[3], double angular_velocity[3])
{
    const int mesh = mesh_handle.index;
    if (!d) return DEM_ERR_NULL;
    if (mesh < 0 || mesh >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    if (velocity) memcpy(velocity, d->meshes[mesh].velocity, 3 * sizeof(double));
    if (angular_velocity) memcpy(angular_velocity, d->meshes[mesh].omega, 3 * sizeof(double));
    return DEM_OK;
}
