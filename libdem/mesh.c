/* Mesh walls: from an STL file or caller arrays to a welded triangle mesh with edge
 * adjacency (coincident vertices merged within a tolerance, zero-area triangles dropped and
 * counted), and the queries on it. Motion and load control: mesh_motion.c; contacts:
 * mesh_contact.c; candidate search: mesh_bins.c. */
#include "stl.h"
#include "triangle.h"
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

/* ---- a small open-addressing hash map from 3 int64 keys to an int32 ---------------- */
typedef struct hmap {
    int64_t *keys; /* 3 per slot */
    int32_t *val;  /* -1: empty */
    uint64_t mask;
} hmap;

static int hmap_init(hmap *h, int64_t n)
{
    uint64_t cap = 16;
    while (cap < 2 * (uint64_t)n) cap *= 2;
    h->keys = malloc(cap * 3 * sizeof(int64_t));
    h->val = malloc(cap * sizeof(int32_t));
    h->mask = cap - 1;
    if (!h->keys || !h->val) return 0;
    for (uint64_t k = 0; k < cap; k++) h->val[k] = -1;
    return 1;
}

static void hmap_free(hmap *h)
{
    free(h->keys);
    free(h->val);
}

/* Slot of key (a, b, c): the one holding it, or the empty one where it would go. */
static uint64_t hmap_slot(const hmap *h, int64_t a, int64_t b, int64_t c)
{
    uint64_t x = (uint64_t)a * 0x9E3779B97F4A7C15ull ^ (uint64_t)b * 0xC2B2AE3D27D4EB4Full ^ (uint64_t)c * 0x165667B19E3779F9ull;
    x ^= x >> 29;
    for (uint64_t s = x & h->mask;; s = (s + 1) & h->mask) {
        if (h->val[s] < 0) return s;
        const int64_t *k = h->keys + 3 * s;
        if (k[0] == a && k[1] == b && k[2] == c) return s;
    }
}

static void hmap_put(hmap *h, uint64_t s, int64_t a, int64_t b, int64_t c, int32_t v)
{
    h->keys[3 * s] = a;
    h->keys[3 * s + 1] = b;
    h->keys[3 * s + 2] = c;
    h->val[s] = v;
}

/* ---- building ------------------------------------------------------------------------ */
void dem_mesh_free(mesh_wall *m)
{
    free(m->x_ref);
    free(m->x);
    free(m->x_build);
    free(m->tri);
    free(m->tri_edge);
    free(m->edge_ntri);
    free(m->normal);
    free(m->bin_start);
    free(m->bin_tri);
    free(m->x_binned);
    memset(m, 0, sizeof *m);
}

void dem_mesh_free_all(dem_domain *d)
{
    for (int k = 0; k < d->n_meshes; k++) dem_mesh_free(&d->meshes[k]);
    free(d->meshes);
    free(d->mesh_scratch);
    tri_list *tl[2] = {&d->tris_cur, &d->tris_old};
    for (int k = 0; k < 2; k++) {
        free(tl[k]->start);
        free(tl[k]->mesh);
        free(tl[k]->tri);
        free(tl[k]->active);
        free(tl[k]->hist);
        free(tl[k]->force);
        free(tl[k]->torque);
        free(tl[k]->point);
        free(tl[k]->normal);
    }
}

/* Welds the corners of n triangles (9 doubles each, already scaled) into m. Fails with a
 * message when nothing usable remains. */
static dem_status build_mesh(dem_domain *d, const double *corner, int64_t n, double tol_user, mesh_wall *m,
                             const char *what)
{
    memset(m, 0, sizeof *m);
    m->input_triangles = n;
    if (n <= 0) return dem_fail(d, DEM_ERR_FORMAT, "%s: the mesh has no triangles", what);
    if (n > INT32_MAX / 3) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: too many triangles (%lld)", what, (long long)n);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t k = 0; k < 3 * n; k++)
        for (int a = 0; a < 3; a++) {
            double v = corner[3 * k + a];
            if (!dem_is_finite(v))
                return dem_fail(d, DEM_ERR_FORMAT, "%s: triangle %lld has a non-finite coordinate", what, (long long)(k / 3));
            if (v < lo[a]) lo[a] = v;
            if (v > hi[a]) hi[a] = v;
        }
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(diag > 0.0)) return dem_fail(d, DEM_ERR_FORMAT, "%s: all vertices coincide (zero-size mesh)", what);
    double tol = tol_user > 0.0 ? tol_user : 1e-6 * diag;
    if (diag / tol > 1e15)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: weld_tolerance %g m is too small for a mesh %g m across", what, tol,
                        diag);

    /* weld: vertices hashed by the tolerance cell, matched against the 27 cells around */
    int32_t *vmap = malloc((size_t)(3 * n) * sizeof(int32_t));
    int32_t *next = malloc((size_t)(3 * n) * sizeof(int32_t));
    double *vx = malloc((size_t)(3 * n) * 3 * sizeof(double));
    hmap cells;
    int ok_cells = hmap_init(&cells, 3 * n);
    dem_status st = DEM_OK;
    if (!vmap || !next || !vx || !ok_cells) {
        st = dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", what);
        goto done;
    }
    int32_t nv = 0;
    for (int64_t k = 0; k < 3 * n; k++) {
        const double *p = corner + 3 * k;
        int64_t q[3];
        for (int a = 0; a < 3; a++) q[a] = (int64_t)floor((p[a] - lo[a]) / tol);
        int32_t found = -1;
        for (int dz = -1; dz <= 1 && found < 0; dz++)
            for (int dy = -1; dy <= 1 && found < 0; dy++)
                for (int dx = -1; dx <= 1 && found < 0; dx++) {
                    uint64_t s = hmap_slot(&cells, q[0] + dx, q[1] + dy, q[2] + dz);
                    for (int32_t v = cells.val[s]; v >= 0; v = next[v])
                        if (tri_dist2(p, vx + 3 * v) <= tol * tol) {
                            found = v;
                            break;
                        }
                }
        if (found < 0) {
            found = nv++;
            memcpy(vx + 3 * found, p, 3 * sizeof(double));
            uint64_t s = hmap_slot(&cells, q[0], q[1], q[2]);
            next[found] = cells.val[s]; /* -1 when the cell was empty */
            hmap_put(&cells, s, q[0], q[1], q[2], found);
        }
        vmap[k] = found;
    }

    /* keep triangles with three distinct vertices and a non-zero area */
    m->tri = malloc((size_t)(3 * n) * sizeof(int32_t));
    if (!m->tri) {
        st = dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", what);
        goto done;
    }
    int64_t nt = 0;
    const double min_cross = 1e-12 * diag * diag;
    for (int64_t t = 0; t < n; t++) {
        int32_t a = vmap[3 * t], b = vmap[3 * t + 1], c = vmap[3 * t + 2];
        if (a == b || b == c || c == a) continue;
        double u[3], w[3];
        for (int k = 0; k < 3; k++) {
            u[k] = vx[3 * b + k] - vx[3 * a + k];
            w[k] = vx[3 * c + k] - vx[3 * a + k];
        }
        double cx = u[1] * w[2] - u[2] * w[1], cy = u[2] * w[0] - u[0] * w[2], cz = u[0] * w[1] - u[1] * w[0];
        if (sqrt(cx * cx + cy * cy + cz * cz) <= min_cross) continue;
        m->tri[3 * nt] = a;
        m->tri[3 * nt + 1] = b;
        m->tri[3 * nt + 2] = c;
        nt++;
    }
    m->skipped_degenerate = n - nt;
    if (nt == 0) {
        st = dem_fail(d, DEM_ERR_FORMAT, "%s: all %lld triangles have zero area", what, (long long)n);
        goto done;
    }
    m->nt = nt;

    /* compact the vertices to those used (vmap reused: old -> new) */
    for (int32_t v = 0; v < nv; v++) vmap[v] = -1;
    int32_t used = 0;
    for (int64_t k = 0; k < 3 * nt; k++) {
        int32_t v = m->tri[k];
        if (vmap[v] < 0) vmap[v] = used++;
    }
    m->nv = used;
    m->x_ref = malloc((size_t)used * 3 * sizeof(double));
    if (!m->x_ref) {
        st = dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", what);
        goto done;
    }
    for (int32_t v = 0; v < nv; v++)
        if (vmap[v] >= 0) memcpy(m->x_ref + 3 * vmap[v], vx + 3 * v, 3 * sizeof(double));
    for (int64_t k = 0; k < 3 * nt; k++) m->tri[k] = vmap[m->tri[k]];
    if (!dem_mesh_finish(m)) st = dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", what);

done:
    free(vmap);
    free(next);
    free(vx);
    hmap_free(&cells);
    if (st != DEM_OK) dem_mesh_free(m);
    return st;
}

/* Given x_ref, tri, nv, nt: edges, world vertices, normals, identity pose. 0: no memory. */
int dem_mesh_finish(mesh_wall *m)
{
    const int64_t nt = m->nt;
    m->x = malloc((size_t)m->nv * 3 * sizeof(double));
    m->x_build = malloc((size_t)m->nv * 3 * sizeof(double));
    m->normal = malloc((size_t)nt * 3 * sizeof(double));
    m->tri_edge = malloc((size_t)nt * 3 * sizeof(int32_t));
    m->edge_ntri = malloc((size_t)nt * 3 * sizeof(int32_t)); /* at most 3 nt edges */
    hmap edges;
    if (!m->x || !m->x_build || !m->normal || !m->tri_edge || !m->edge_ntri || !hmap_init(&edges, 3 * nt)) return 0;
    /* edges: (min, max) vertex pair -> id */
    int32_t ne = 0;
    for (int64_t t = 0; t < nt; t++)
        for (int e = 0; e < 3; e++) {
            int32_t a = m->tri[3 * t + e], b = m->tri[3 * t + (e + 1) % 3];
            int32_t lo_v = a < b ? a : b, hi_v = a < b ? b : a;
            uint64_t s = hmap_slot(&edges, lo_v, hi_v, 0);
            if (edges.val[s] < 0) {
                hmap_put(&edges, s, lo_v, hi_v, 0, ne);
                m->edge_ntri[ne++] = 0;
            }
            m->tri_edge[3 * t + e] = edges.val[s];
            m->edge_ntri[edges.val[s]]++;
        }
    hmap_free(&edges);
    m->ne = ne;
    for (int a = 0; a < 9; a++) m->rot[a] = (a % 4 == 0) ? 1.0 : 0.0;
    dem_mesh_update_world(m);
    memcpy(m->x_build, m->x, (size_t)m->nv * 3 * sizeof(double));
    return 1;
}

/* Particle k (of n at x, r) that mesh m cuts, or -1. The particles are hashed into a grid
 * of cells of the largest diameter; each triangle checks the cells its inflated box covers. */
static int64_t first_cut_particle(const dem_domain *d, const mesh_wall *m, int64_t n, const double *x, const double *r)
{
    if (n == 0) return -1;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, rmax = 0.0;
    for (int64_t i = 0; i < n; i++) {
        rmax = fmax(rmax, r[i]);
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], x[3 * i + a]);
            hi[a] = fmax(hi[a], x[3 * i + a]);
        }
    }
    int nc[3];
    double cs = 2.0 * rmax;
    for (;;) { /* at most ~2 cells per particle */
        int64_t total = 1;
        for (int a = 0; a < 3; a++) {
            double c = floor((hi[a] - lo[a]) / cs) + 1.0;
            nc[a] = c > 1e6 ? 1000000 : (int)c;
            total *= nc[a];
        }
        if (total <= 2 * n + 64) break;
        cs *= 1.5;
    }
    int64_t ncell = (int64_t)nc[0] * nc[1] * nc[2];
    int64_t *head = malloc((size_t)ncell * sizeof *head), *next = malloc((size_t)n * sizeof *next);
    if (!head || !next) { /* no memory for the grid: check everything */
        free(head);
        free(next);
        head = NULL;
    }
    int64_t found = -1;
    const double keep = 1.0 - d->def.insert_overlap_ratio;
#define CELL(i_, a_) ((int)fmin(fmax(floor((x[3 * (i_) + (a_)] - lo[(a_)]) / cs), 0.0), nc[(a_)] - 1.0))
    if (head) {
        for (int64_t c = 0; c < ncell; c++) head[c] = -1;
        for (int64_t i = n - 1; i >= 0; i--) {
            int64_t c = ((int64_t)CELL(i, 2) * nc[1] + CELL(i, 1)) * nc[0] + CELL(i, 0);
            next[i] = head[c];
            head[c] = i;
        }
    }
    for (int64_t t = 0; t < m->nt && found < 0; t++) {
        const int32_t *tv = m->tri + 3 * t;
        const double *A = m->x + 3 * tv[0], *B = m->x + 3 * tv[1], *C = m->x + 3 * tv[2];
        int c0[3], c1[3];
        int outside = 0;
        for (int a = 0; a < 3; a++) {
            double tlo = fmin(A[a], fmin(B[a], C[a])) - rmax, thi = fmax(A[a], fmax(B[a], C[a])) + rmax;
            if (thi < lo[a] || tlo > hi[a]) outside = 1;
            c0[a] = (int)fmax(floor((tlo - lo[a]) / cs), 0.0);
            c1[a] = (int)fmin(floor((thi - lo[a]) / cs), nc[a] - 1.0);
        }
        if (outside) continue;
        if (!head) { /* fallback: every particle */
            for (int64_t i = 0; i < n && found < 0; i++) {
                double q[3];
                tri_closest_point(x + 3 * i, A, B, C, q);
                if (tri_dist2(x + 3 * i, q) < keep * keep * r[i] * r[i]) found = i;
            }
            continue;
        }
        for (int cz = c0[2]; cz <= c1[2]; cz++)
            for (int cy = c0[1]; cy <= c1[1]; cy++)
                for (int cx = c0[0]; cx <= c1[0]; cx++)
                    for (int64_t i = head[((int64_t)cz * nc[1] + cy) * nc[0] + cx]; i >= 0; i = next[i]) {
                        double q[3];
                        tri_closest_point(x + 3 * i, A, B, C, q);
                        if (tri_dist2(x + 3 * i, q) < keep * keep * r[i] * r[i] && (found < 0 || i < found)) found = i;
                    }
    }
#undef CELL
    free(head);
    free(next);
    return found;
}

int64_t dem_meshes_cut_particles(const dem_domain *d, int64_t n, const double *x, const double *r, int *which_mesh)
{
    for (int k = 0; k < d->n_meshes; k++) {
        int64_t i = first_cut_particle(d, &d->meshes[k], n, x, r);
        if (i >= 0) {
            *which_mesh = k;
            return i;
        }
    }
    return -1;
}

/* Appends a finished mesh to the domain (takes its arrays, frees them on failure). */
dem_status dem_mesh_append(dem_domain *d, mesh_wall *m, const char *what, int *out)
{
    if (d->n_meshes == d->cap_meshes) {
        int c = d->cap_meshes ? 2 * d->cap_meshes : 4;
        mesh_wall *p = dem_realloc_array(d->meshes, (size_t)c, sizeof *p);
        if (!p) {
            dem_mesh_free(m);
            return dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", what);
        }
        d->meshes = p;
        d->cap_meshes = c;
    }
    d->meshes[d->n_meshes] = *m;
    *out = d->n_meshes++;
    d->need_rebuild = 1;
    d->forces_valid = 0;
    d->rayleigh_cache = -1.0;
    dem_clear_error(d);
    return DEM_OK;
}

static dem_status add_built_mesh(dem_domain *d, mesh_wall *m, const char *what, int *out)
{
    int64_t cut = first_cut_particle(d, m, d->n, d->x, d->radius);
    if (cut >= 0) {
        dem_mesh_free(m);
        return dem_fail(d, DEM_ERR_OVERLAP, "%s: the mesh cuts particle id %lld", what, (long long)d->id[cut]);
    }
    return dem_mesh_append(d, m, what, out);
}

static dem_status check_def(dem_domain *d, const dem_mesh_def *def, const char *fn)
{
    if (!(def->scale > 0.0) || !dem_is_finite(def->scale))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: scale must be finite and > 0, got %g", fn, def->scale);
    for (int a = 0; a < 3; a++)
        if (!dem_is_finite(def->offset[a])) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: offset is not finite", fn);
    if (!dem_is_finite(def->weld_tolerance))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: weld_tolerance is not finite", fn);
    if (def->material < 0 || def->material >= d->n_materials)
        return dem_fail(d, DEM_ERR_UNKNOWN_MATERIAL, "%s: unknown material %d (%d materials exist)", fn, def->material,
                        d->n_materials);
    return DEM_OK;
}

static void transform_corners(double *xyz, int64_t n_points, const dem_mesh_def *def)
{
    for (int64_t k = 0; k < n_points; k++)
        for (int a = 0; a < 3; a++) xyz[3 * k + a] = xyz[3 * k + a] * def->scale + def->offset[a];
}

dem_status dem_mesh_wall_add_stl(dem_domain *d, const char *path, const dem_mesh_def *def, int *out)
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
    s = build_mesh(d, soup.xyz, soup.n, def->weld_tolerance, &m, what);
    free(soup.xyz);
    if (s != DEM_OK) return s;
    m.material = def->material;
    return add_built_mesh(d, &m, what, out);
}

dem_status dem_mesh_wall_add(dem_domain *d, int64_t n_vertices, const double *vertices, int64_t n_triangles,
                             const int32_t *triangles, const dem_mesh_def *def, int *out)
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
    double *corner = malloc((size_t)n_triangles * 9 * sizeof(double));
    if (!corner) return dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", fn);
    for (int64_t k = 0; k < 3 * n_triangles; k++) memcpy(corner + 3 * k, vertices + 3 * (int64_t)triangles[k], 3 * sizeof(double));
    transform_corners(corner, 3 * n_triangles, def);
    mesh_wall m;
    s = build_mesh(d, corner, n_triangles, def->weld_tolerance, &m, fn);
    free(corner);
    if (s != DEM_OK) return s;
    m.material = def->material;
    return add_built_mesh(d, &m, fn, out);
}

/* ---- queries --------------------------------------------------------------------------- */
int dem_mesh_wall_count(const dem_domain *d) { return d ? d->n_meshes : 0; }

dem_status dem_mesh_wall_info(const dem_domain *d, int k, dem_mesh_info *info)
{
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

/* Room for the mesh's `count` vertices or triangles in a caller's buffer? */
static dem_status mesh_room(const dem_domain *d, int64_t capacity, int64_t count, const char *fn)
{
    if (capacity < count)
        return dem_fail((dem_domain *)d, DEM_ERR_INVALID_ARGUMENT, "%s: room for %lld, the mesh has %lld", fn,
                        (long long)capacity, (long long)count);
    return DEM_OK;
}

dem_status dem_mesh_wall_get_vertices(const dem_domain *d, int k, double *vertices, int64_t capacity)
{
    if (!d || !vertices) return DEM_ERR_NULL;
    if (k < 0 || k >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    if (mesh_room(d, capacity, d->meshes[k].nv, "dem_mesh_wall_get_vertices") != DEM_OK) return DEM_ERR_INVALID_ARGUMENT;
    memcpy(vertices, d->meshes[k].x, (size_t)d->meshes[k].nv * 3 * sizeof(double));
    return DEM_OK;
}

dem_status dem_mesh_wall_get_triangles(const dem_domain *d, int k, int32_t *triangles, int64_t capacity)
{
    if (!d || !triangles) return DEM_ERR_NULL;
    if (k < 0 || k >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    if (mesh_room(d, capacity, d->meshes[k].nt, "dem_mesh_wall_get_triangles") != DEM_OK) return DEM_ERR_INVALID_ARGUMENT;
    memcpy(triangles, d->meshes[k].tri, (size_t)d->meshes[k].nt * 3 * sizeof(int32_t));
    return DEM_OK;
}

void dem_mesh_total_force(const dem_domain *d, int mesh, double force[3])
{
    force[0] = force[1] = force[2] = 0.0;
    const tri_list *tl = &d->tris_cur;
    for (int64_t k = 0; k < tl->count; k++)
        if (tl->mesh[k] == mesh && tl->active[k])
            for (int a = 0; a < 3; a++) force[a] -= tl->force[3 * k + a];
}

dem_status dem_mesh_wall_force(const dem_domain *d, int mesh, const double point[3], double force[3], double torque[3])
{
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

dem_status dem_mesh_wall_triangle_forces(const dem_domain *d, int mesh, double *forces, int64_t capacity)
{
    if (!d || !forces) return DEM_ERR_NULL;
    if (mesh < 0 || mesh >= d->n_meshes) return DEM_ERR_UNKNOWN_WALL;
    if (mesh_room(d, capacity, d->meshes[mesh].nt, "dem_mesh_wall_triangle_forces") != DEM_OK) return DEM_ERR_INVALID_ARGUMENT;
    memset(forces, 0, (size_t)d->meshes[mesh].nt * 3 * sizeof(double));
    const tri_list *tl = &d->tris_cur;
    for (int64_t k = 0; k < tl->count; k++)
        if (tl->mesh[k] == mesh && tl->active[k])
            for (int a = 0; a < 3; a++) forces[3 * (int64_t)tl->tri[k] + a] -= tl->force[3 * k + a];
    return DEM_OK;
}

dem_status dem_mesh_wall_stress(const dem_domain *d, int mesh, const double normal[3], double area, double *sn,
                                double *tau)
{
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
