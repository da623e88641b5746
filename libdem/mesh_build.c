/* Building a mesh wall: welding triangle corners into vertices (coincident corners merged
 * within a tolerance, zero-area triangles dropped and counted), edge adjacency, appending the
 * finished mesh to the domain, freeing it. The API that calls it: mesh.c. */
#include "triangle.h"
#include "internal.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    h->keys = dem_malloc(cap * 3 * sizeof(int64_t));
    h->val = dem_malloc(cap * sizeof(int32_t));
    h->mask = cap - 1;
    if (!h->keys || !h->val) return 0;
    for (uint64_t k = 0; k < cap; k++) h->val[k] = -1;
    return 1;
}

static void hmap_free(hmap *h)
{
    dem_free(h->keys);
    dem_free(h->val);
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
    dem_free(m->x_ref);
    dem_free(m->x);
    dem_free(m->x_build);
    dem_free(m->tri);
    dem_free(m->tri_edge);
    dem_free(m->edge_ntri);
    dem_free(m->normal);
    dem_free(m->bin_start);
    dem_free(m->bin_tri);
    dem_free(m->x_binned);
    memset(m, 0, sizeof *m);
}

void dem_mesh_free_all(dem_domain *d)
{
    for (int k = 0; k < d->n_meshes; k++) dem_mesh_free(&d->meshes[k]);
    dem_free(d->meshes);
    dem_free(d->mesh_scratch);
    tri_list *tl[2] = {&d->tris_cur, &d->tris_old};
    for (int k = 0; k < 2; k++) {
        dem_free(tl[k]->start);
        dem_free(tl[k]->mesh);
        dem_free(tl[k]->tri);
        dem_free(tl[k]->active);
        dem_free(tl[k]->hist);
        dem_free(tl[k]->force);
        dem_free(tl[k]->torque);
        dem_free(tl[k]->point);
        dem_free(tl[k]->normal);
        dem_free(tl[k]->gap);
    }
}

/* Welds the corners of n triangles (9 doubles each, already scaled) into m. Fails with a
 * message when nothing usable remains. */
dem_status dem_mesh_build(dem_domain *d, const double *corner, int64_t n, double tol_user, mesh_wall *m,
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
    int32_t *vmap = dem_malloc((size_t)(3 * n) * sizeof(int32_t));
    int32_t *next = dem_malloc((size_t)(3 * n) * sizeof(int32_t));
    double *vx = dem_malloc((size_t)(3 * n) * 3 * sizeof(double));
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
    m->tri = dem_malloc((size_t)(3 * n) * sizeof(int32_t));
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
    m->x_ref = dem_malloc((size_t)used * 3 * sizeof(double));
    if (!m->x_ref) {
        st = dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", what);
        goto done;
    }
    for (int32_t v = 0; v < nv; v++)
        if (vmap[v] >= 0) memcpy(m->x_ref + 3 * vmap[v], vx + 3 * v, 3 * sizeof(double));
    for (int64_t k = 0; k < 3 * nt; k++) m->tri[k] = vmap[m->tri[k]];
    if (!dem_mesh_finish(m)) st = dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", what);

done:
    dem_free(vmap);
    dem_free(next);
    dem_free(vx);
    hmap_free(&cells);
    if (st != DEM_OK) dem_mesh_free(m);
    return st;
}

/* Given x_ref, tri, nv, nt: edges, world vertices, normals, identity pose. 0: no memory. */
int dem_mesh_finish(mesh_wall *m)
{
    const int64_t nt = m->nt;
    m->x = dem_malloc((size_t)m->nv * 3 * sizeof(double));
    m->x_build = dem_malloc((size_t)m->nv * 3 * sizeof(double));
    m->normal = dem_malloc((size_t)nt * 3 * sizeof(double));
    m->tri_edge = dem_malloc((size_t)nt * 3 * sizeof(int32_t));
    m->edge_ntri = dem_malloc((size_t)nt * 3 * sizeof(int32_t)); /* at most 3 nt edges */
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
