/* Mesh walls, the API: from an STL file or caller arrays (scaled, offset, welded:
 * mesh_build.c; refused when it cuts a particle: mesh_cut.c) to a wall of the domain, and what
 * it is (info, vertices, triangles). Motion and load control: mesh_motion.c; contacts:
 * mesh_contact.c; candidate search: mesh_bins.c; forces on it: mesh_forces.c. */
#include "stl.h"
#include "internal.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

dem_mesh_def dem_default_mesh_def(void)
{
    dem_mesh_def m;
    memset(&m, 0, sizeof m);
    m.scale = 1.0;
    return m;
}

static dem_status add_built_mesh(dem_domain *d, mesh_wall *m, const char *what, dem_mesh_wall *out)
{
    int64_t cut = dem_mesh_first_cut(d, m, d->n, d->x, d->radius);
    if (cut >= 0) {
        dem_mesh_free(m);
        return dem_fail(d, DEM_ERR_OVERLAP, "%s: the mesh cuts particle id %lld", what, (long long)d->id[cut]);
    }
    int k;
    dem_status s = dem_mesh_append(d, m, what, &k);
    if (s == DEM_OK && out) out->index = k;
    return s;
}

static dem_status check_def(dem_domain *d, const dem_mesh_def *def, const char *fn)
{
    if (!(def->scale > 0.0) || !dem_is_finite(def->scale))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: scale must be finite and > 0, got %g", fn, def->scale);
    for (int a = 0; a < 3; a++)
        if (!dem_is_finite(def->offset[a])) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: offset is not finite", fn);
    if (!dem_is_finite(def->weld_tolerance))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: weld_tolerance is not finite", fn);
    if (def->material.index < 0 || def->material.index >= d->n_materials)
        return dem_fail(d, DEM_ERR_UNKNOWN_MATERIAL, "%s: unknown material %d (%d materials exist)", fn,
                        (int)def->material.index,
                        d->n_materials);
    return DEM_OK;
}

static void transform_corners(double *xyz, int64_t n_points, const dem_mesh_def *def)
{
    for (int64_t k = 0; k < n_points; k++)
        for (int a = 0; a < 3; a++) xyz[3 * k + a] = xyz[3 * k + a] * def->scale + def->offset[a];
}

dem_status dem_mesh_wall_add_stl(dem_domain *d, const char *path, const dem_mesh_def *def, dem_mesh_wall *out)
{
    if (!d) return DEM_ERR_NULL;
    if (!path || !def || !out) return dem_fail(d, DEM_ERR_NULL, "dem_mesh_wall_add_stl: path, def and mesh must not be NULL");
    dem_status s = check_def(d, def, "dem_mesh_wall_add_stl");
    if (s != DEM_OK) return s;
    stl_soup soup;
    char err[480];
    int rc = dem_stl_read_file(path, &soup, err, sizeof err);
    if (rc != STL_OK)
        return dem_fail(d, rc == STL_IO ? DEM_ERR_IO : rc == STL_NO_MEMORY ? DEM_ERR_NO_MEMORY : DEM_ERR_FORMAT,
                        "dem_mesh_wall_add_stl: %s", err);
    transform_corners(soup.xyz, 3 * soup.n, def);
    mesh_wall m;
    char what[300];
    snprintf(what, sizeof what, "dem_mesh_wall_add_stl: '%s'", path);
    s = dem_mesh_build(d, soup.xyz, soup.n, def->weld_tolerance, &m, what);
    dem_free(soup.xyz);
    if (s != DEM_OK) return s;
    m.material = def->material.index;
    return add_built_mesh(d, &m, what, out);
}

dem_status dem_mesh_wall_add(dem_domain *d, int64_t n_vertices, const double *vertices, int64_t n_triangles,
                             const int32_t *triangles, const dem_mesh_def *def, dem_mesh_wall *out)
{
    const char *fn = "dem_mesh_wall_add";
    if (!d) return DEM_ERR_NULL;
    if (!vertices || !triangles || !def || !out)
        return dem_fail(d, DEM_ERR_NULL, "%s: vertices, triangles, def and mesh must not be NULL", fn);
    if (n_vertices < 3 || n_triangles < 1)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: need >= 3 vertices and >= 1 triangle, got %lld and %lld", fn,
                        (long long)n_vertices, (long long)n_triangles);
    if (n_triangles > INT32_MAX / 3)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: too many triangles (%lld)", fn, (long long)n_triangles);
    dem_status s = check_def(d, def, fn);
    if (s != DEM_OK) return s;
    for (int64_t k = 0; k < 3 * n_triangles; k++)
        if (triangles[k] < 0 || triangles[k] >= n_vertices)
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: triangle %lld names vertex %d (of %lld)", fn,
                            (long long)(k / 3), triangles[k], (long long)n_vertices);
    double *corner = dem_malloc((size_t)n_triangles * 9 * sizeof(double));
    if (!corner) return dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", fn);
    for (int64_t k = 0; k < 3 * n_triangles; k++) memcpy(corner + 3 * k, vertices + 3 * (int64_t)triangles[k], 3 * sizeof(double));
    transform_corners(corner, 3 * n_triangles, def);
    mesh_wall m;
    s = dem_mesh_build(d, corner, n_triangles, def->weld_tolerance, &m, fn);
    dem_free(corner);
    if (s != DEM_OK) return s;
    m.material = def->material.index;
    return add_built_mesh(d, &m, fn, out);
}

/* ---- queries --------------------------------------------------------------------------- */
int dem_mesh_wall_count(const dem_domain *d) { return d ? d->n_meshes : 0; }

dem_status dem_mesh_wall_info(const dem_domain *d, dem_mesh_wall k_handle, dem_mesh_info *info)
{
    const int k = k_handle.index;
    if (!d || !info) return DEM_ERR_NULL;
    if (k < 0 || k >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    const mesh_wall *m = &d->meshes[k];
    memset(info, 0, sizeof *info);
    info->vertex_count = m->nv;
    info->triangle_count = m->nt;
    info->edge_count = m->ne;
    for (int64_t e = 0; e < m->ne; e++) {
        info->boundary_edge_count += m->edge_ntri[e] == 1;
        info->nonmanifold_edge_count += m->edge_ntri[e] > 2;
    }
    info->skipped_degenerate = m->skipped_degenerate;
    info->input_triangle_count = m->input_triangles;
    for (int a = 0; a < 3; a++) {
        info->lo[a] = INFINITY;
        info->hi[a] = -INFINITY;
    }
    for (int64_t v = 0; v < m->nv; v++)
        for (int a = 0; a < 3; a++) {
            info->lo[a] = fmin(info->lo[a], m->x[3 * v + a]);
            info->hi[a] = fmax(info->hi[a], m->x[3 * v + a]);
        }
    return DEM_OK;
}

dem_status dem_mesh_wall_get_vertices(const dem_domain *d, dem_mesh_wall k_handle, double *vertices, int64_t capacity)
{
    const int k = k_handle.index;
    if (!d || !vertices) return DEM_ERR_NULL;
    if (k < 0 || k >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    if (dem_check_room(d, capacity, d->meshes[k].nv, "vertices", "dem_mesh_wall_get_vertices") != DEM_OK) return DEM_ERR_INVALID_ARGUMENT;
    memcpy(vertices, d->meshes[k].x, (size_t)d->meshes[k].nv * 3 * sizeof(double));
    return DEM_OK;
}

dem_status dem_mesh_wall_get_triangles(const dem_domain *d, dem_mesh_wall k_handle, int32_t *triangles, int64_t capacity)
{
    const int k = k_handle.index;
    if (!d || !triangles) return DEM_ERR_NULL;
    if (k < 0 || k >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    if (dem_check_room(d, capacity, d->meshes[k].nt, "triangles", "dem_mesh_wall_get_triangles") != DEM_OK) return DEM_ERR_INVALID_ARGUMENT;
    memcpy(triangles, d->meshes[k].tri, (size_t)d->meshes[k].nt * 3 * sizeof(int32_t));
    return DEM_OK;
}
