/* Analytic axis-aligned plane walls. */
#include "internal.h"
#include <string.h>

dem_plane_wall_def dem_default_plane_wall_def(void)
{
    dem_plane_wall_def w;
    memset(&w, 0, sizeof w);
    w.axis = 2;
    w.side = 1;
    w.position = 0.0;
    w.material.index = 0;
    return w;
}

static dem_status check_velocity(dem_domain *d, const double *v, const char *fn)
{
    for (int a = 0; a < 3; a++)
        if (!dem_is_finite(v[a])) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: velocity %d is not finite", fn, a);
    return DEM_OK;
}

dem_status dem_plane_wall_add(dem_domain *d, const dem_plane_wall_def *def, dem_plane_wall *wall)
{
    if (!d) return DEM_ERR_NULL;
    if (!def || !wall) return dem_fail(d, DEM_ERR_NULL, "dem_plane_wall_add: def and wall must not be NULL");
    if (def->axis < 0 || def->axis > 2)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_plane_wall_add: axis must be 0, 1 or 2, got %d", def->axis);
    if (def->side != 1 && def->side != -1)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_plane_wall_add: side must be +1 or -1, got %d", def->side);
    if (!dem_is_finite(def->position))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_plane_wall_add: position is not finite");
    if (def->material.index < 0 || def->material.index >= d->n_materials)
        return dem_fail(d, DEM_ERR_UNKNOWN_MATERIAL, "dem_plane_wall_add: unknown material %d (%d materials exist)",
                        (int)def->material.index, d->n_materials);
    dem_status s = check_velocity(d, def->velocity, "dem_plane_wall_add");
    if (s != DEM_OK) return s;
    for (int64_t i = 0; i < d->n; i++) {
        double dist = (d->x[3 * i + def->axis] - def->position) * def->side;
        if (dist < d->radius[i] * (1.0 - d->def.insert_overlap_ratio))
            return dem_fail(d, DEM_ERR_OVERLAP, "dem_plane_wall_add: the wall cuts particle id %lld", (long long)d->id[i]);
    }
    if (d->n_walls == d->cap_walls) {
        int c = d->cap_walls ? 2 * d->cap_walls : 8;
        plane_wall *p = dem_realloc_array(d->walls, (size_t)c, sizeof *p);
        if (!p) return dem_fail(d, DEM_ERR_NO_MEMORY, "dem_plane_wall_add: out of memory");
        d->walls = p;
        d->cap_walls = c;
    }
    plane_wall *w = &d->walls[d->n_walls];
    memset(w, 0, sizeof *w);
    w->def = *def;
    w->normal[def->axis] = (double)def->side;
    wall->index = d->n_walls++;
    d->need_rebuild = 1;
    d->forces_valid = 0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_plane_wall_set_velocity(dem_domain *d, dem_plane_wall wall_handle, const double velocity[3])
{
    const int wall = wall_handle.index;
    if (!d) return DEM_ERR_NULL;
    if (!velocity) return dem_fail(d, DEM_ERR_NULL, "dem_plane_wall_set_velocity: velocity must not be NULL");
    if (wall < 0 || wall >= d->n_walls)
        return dem_fail(d, DEM_ERR_UNKNOWN_WALL, "dem_plane_wall_set_velocity: unknown wall %d", wall);
    dem_status s = check_velocity(d, velocity, "dem_plane_wall_set_velocity");
    if (s != DEM_OK) return s;
    for (int a = 0; a < 3; a++) d->walls[wall].def.velocity[a] = velocity[a];
    d->forces_valid = 0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_plane_wall_force(const dem_domain *d, dem_plane_wall wall_handle, double force[3])
{
    const int wall = wall_handle.index;
    if (!d || !force) return DEM_ERR_NULL;
    if (wall < 0 || wall >= d->n_walls) return DEM_ERR_UNKNOWN_WALL;
    force[0] = force[1] = force[2] = 0.0;
    const wall_list *wl = &d->walls_cur;
    for (int64_t k = 0; k < wl->count; k++)
        if (wl->wall[k] == wall)
            for (int a = 0; a < 3; a++) force[a] -= wl->force[3 * k + a];
    return DEM_OK;
}
