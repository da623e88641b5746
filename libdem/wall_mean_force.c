/* Time-averaged wall force, for mesh and plane walls: the integral of the force the particles
 * exert on a wall over every step since a reset. A snapshot of a lid's force in a sheared bed
 * rattles by tens of per cent from step to step; rigs that want a stress want this average. */
#include "internal.h"
#include <string.h>

static void planes_accumulate(dem_domain *d, double dt)
{
    int any = 0;
    for (int w = 0; w < d->n_walls; w++) {
        plane_wall *p = &d->walls[w];
        if (p->averaging) p->averaged_time += dt;
        any |= p->averaging;
    }
    if (!any || d->n == 0) return;
    const wall_list *wl = &d->walls_cur;
    for (int64_t k = 0; k < wl->count; k++) {
        plane_wall *p = &d->walls[wl->wall[k]];
        if (p->averaging)
            for (int a = 0; a < 3; a++) p->impulse[a] -= wl->force[3 * k + a] * dt; /* wl->force acts on the particle */
    }
}

void dem_walls_accumulate_mean_force(dem_domain *d, double dt)
{
    planes_accumulate(d, dt);
    int any = 0;
    for (int k = 0; k < d->n_meshes; k++) {
        mesh_wall *m = &d->meshes[k];
        if (m->averaging) m->averaged_time += dt;
        any |= m->averaging;
    }
    if (!any || d->n == 0) return;
    const tri_list *tl = &d->tris_cur;
    for (int64_t k = 0; k < tl->count; k++) {
        if (!tl->active[k]) continue;
        mesh_wall *m = &d->meshes[tl->mesh[k]];
        if (!m->averaging) continue;
        const double *fk = tl->force + 3 * k, *q = tl->point + 3 * k;
        const double f[3] = {-fk[0] * dt, -fk[1] * dt, -fk[2] * dt}; /* tl->force acts on the particle */
        for (int a = 0; a < 3; a++) m->impulse[a] += f[a];
        m->moment_impulse[0] += q[1] * f[2] - q[2] * f[1];
        m->moment_impulse[1] += q[2] * f[0] - q[0] * f[2];
        m->moment_impulse[2] += q[0] * f[1] - q[1] * f[0];
    }
}

dem_status dem_mesh_wall_reset_mean_force(dem_domain *d, dem_mesh_wall mesh_handle)
{
    const int mesh = mesh_handle.index;
    if (!d) return DEM_ERR_NULL;
    if (mesh < 0 || mesh >= d->n_meshes)
        return dem_fail(d, DEM_ERR_UNKNOWN_WALL, "dem_mesh_wall_reset_mean_force: unknown mesh wall %d (%d exist)", mesh,
                        d->n_meshes);
    mesh_wall *m = &d->meshes[mesh];
    m->averaging = 1;
    memset(m->impulse, 0, sizeof m->impulse);
    memset(m->moment_impulse, 0, sizeof m->moment_impulse);
    m->averaged_time = 0.0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_mesh_wall_mean_force(const dem_domain *d, dem_mesh_wall mesh_handle, const double point[3], double force[3],
                                    double torque[3], double *seconds)
{
    const int mesh = mesh_handle.index;
    if (!d || !force) return DEM_ERR_NULL;
    if (mesh < 0 || mesh >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    const mesh_wall *m = &d->meshes[mesh];
    const double t = m->averaged_time, inv = t > 0.0 ? 1.0 / t : 0.0;
    const double origin[3] = {0.0, 0.0, 0.0};
    const double *p = point ? point : origin;
    for (int a = 0; a < 3; a++) force[a] = m->impulse[a] * inv;
    if (torque) { /* about p: M_p = M_0 - p x F */
        const double *f = force;
        double m0[3];
        for (int a = 0; a < 3; a++) m0[a] = m->moment_impulse[a] * inv;
        torque[0] = m0[0] - (p[1] * f[2] - p[2] * f[1]);
        torque[1] = m0[1] - (p[2] * f[0] - p[0] * f[2]);
        torque[2] = m0[2] - (p[0] * f[1] - p[1] * f[0]);
    }
    if (seconds) *seconds = t;
    return DEM_OK;
}

dem_status dem_plane_wall_reset_mean_force(dem_domain *d, dem_plane_wall wall_handle)
{
    const int wall = wall_handle.index;
    if (!d) return DEM_ERR_NULL;
    if (wall < 0 || wall >= d->n_walls)
        return dem_fail(d, DEM_ERR_UNKNOWN_WALL, "dem_plane_wall_reset_mean_force: unknown plane wall %d (%d exist)", wall,
                        d->n_walls);
    plane_wall *p = &d->walls[wall];
    p->averaging = 1;
    memset(p->impulse, 0, sizeof p->impulse);
    p->averaged_time = 0.0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_plane_wall_mean_force(const dem_domain *d, dem_plane_wall wall_handle, double force[3], double *seconds)
{
    const int wall = wall_handle.index;
    if (!d || !force) return DEM_ERR_NULL;
    if (wall < 0 || wall >= d->n_walls) return DEM_ERR_UNKNOWN_WALL;
    const plane_wall *p = &d->walls[wall];
    const double t = p->averaged_time, inv = t > 0.0 ? 1.0 / t : 0.0;
    for (int a = 0; a < 3; a++) force[a] = p->impulse[a] * inv;
    if (seconds) *seconds = t;
    return DEM_OK;
}
