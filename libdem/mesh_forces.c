/* What the particles do to a mesh wall: its total force and torque, the force on each
 * triangle, the stress over an area, from the last step's triangle contacts. The servo reads
 * the total force (mesh_motion.c); the time average: wall_mean_force.c. */
#include "internal.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

void dem_mesh_total_force(const dem_domain *d, int mesh, double force[3])
{
    force[0] = force[1] = force[2] = 0.0;
    const tri_list *tl = &d->tris_cur;
    for (int64_t k = 0; k < tl->count; k++)
        if (tl->mesh[k] == mesh && tl->active[k])
            for (int a = 0; a < 3; a++) force[a] -= tl->force[3 * k + a];
}

dem_status dem_mesh_wall_force(const dem_domain *d, dem_mesh_wall mesh_handle, const double point[3], double force[3], double torque[3])
{
    const int mesh = mesh_handle.index;
    if (!d || !force) return DEM_ERR_NULL;
    if (mesh < 0 || mesh >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    const double origin[3] = {0.0, 0.0, 0.0};
    const double *p0 = point ? point : origin;
    double tq[3] = {0.0, 0.0, 0.0};
    force[0] = force[1] = force[2] = 0.0;
    const tri_list *tl = &d->tris_cur;
    for (int64_t k = 0; k < tl->count; k++) {
        if (tl->mesh[k] != mesh || !tl->active[k]) continue;
        const double *fk = tl->force + 3 * k, *q = tl->point + 3 * k;
        double f[3] = {-fk[0], -fk[1], -fk[2]}, r[3] = {q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]};
        for (int a = 0; a < 3; a++) force[a] += f[a];
        tq[0] += r[1] * f[2] - r[2] * f[1];
        tq[1] += r[2] * f[0] - r[0] * f[2];
        tq[2] += r[0] * f[1] - r[1] * f[0];
    }
    if (torque) memcpy(torque, tq, sizeof tq);
    return DEM_OK;
}

dem_status dem_mesh_wall_triangle_forces(const dem_domain *d, dem_mesh_wall mesh_handle, double *forces, int64_t capacity)
{
    const int mesh = mesh_handle.index;
    if (!d || !forces) return DEM_ERR_NULL;
    if (mesh < 0 || mesh >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    if (dem_check_room(d, capacity, d->meshes[mesh].nt, "triangles", "dem_mesh_wall_triangle_forces") != DEM_OK) return DEM_ERR_INVALID_ARGUMENT;
    memset(forces, 0, (size_t)d->meshes[mesh].nt * 3 * sizeof(double));
    const tri_list *tl = &d->tris_cur;
    for (int64_t k = 0; k < tl->count; k++)
        if (tl->mesh[k] == mesh && tl->active[k])
            for (int a = 0; a < 3; a++) forces[3 * (int64_t)tl->tri[k] + a] -= tl->force[3 * k + a];
    return DEM_OK;
}

dem_status dem_mesh_wall_stress(const dem_domain *d, dem_mesh_wall mesh_handle, const double normal[3], double area, double *sn,
                                double *tau)
{
    const int mesh = mesh_handle.index;
    if (!d || !normal || !sn || !tau) return DEM_ERR_NULL;
    if (mesh < 0 || mesh >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    double len = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(area > 0.0) || !(len > 0.0) || !dem_is_finite(area) || !dem_is_finite(len)) return DEM_ERR_INVALID_ARGUMENT;
    double f[3];
    dem_mesh_total_force(d, mesh, f);
    double fn = (f[0] * normal[0] + f[1] * normal[1] + f[2] * normal[2]) / len;
    double s2 = 0.0;
    for (int a = 0; a < 3; a++) {
        double u = f[a] - fn * normal[a] / len;
        s2 += u * u;
    }
    *sn = fn / area;
    *tau = sqrt(s2) / area;
    return DEM_OK;
}
