/* Mesh-triangle candidates for the Verlet scheme: each mesh's triangles are binned into the
 * particle cell grid (every triangle within reach = r_max + skin of some point of a cell is
 * listed there), then each particle keeps the triangles of its own cell that lie within
 * r + skin. A mesh's bins are remade only when the grid or the reach changed or the mesh moved
 * farther than the margin it was binned with (none for a still mesh, a skin for a moving one):
 * the bins only have to hold every triangle that can be within reach, so the candidates are
 * the same whenever they are remade. Histories follow the (particle, mesh, triangle) entries
 * across builds. */
#include "internal.h"
#include "triangle.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

static int64_t grown(int64_t need) { return need + need / 4 + 256; }

static int tri_list_reserve(tri_list *tl, int64_t need)
{
    if (need <= tl->capacity) return 1;
    int64_t c = grown(need);
    void **i32[] = {(void **)&tl->mesh, (void **)&tl->tri};
    void **u8[] = {(void **)&tl->active};
    void **h6[] = {(void **)&tl->hist};
    void **v3[] = {(void **)&tl->force, (void **)&tl->torque, (void **)&tl->point, (void **)&tl->normal};
    void **f1[] = {(void **)&tl->gap};
    if (!dem_realloc_all(i32, 2, (size_t)c, sizeof(int32_t)) || !dem_realloc_all(u8, 1, (size_t)c, 1) ||
        !dem_realloc_all(f1, 1, (size_t)c, sizeof(double)) ||
        !dem_realloc_all(h6, 1, (size_t)c * 6, sizeof(double)) || !dem_realloc_all(v3, 4, (size_t)c * 3, sizeof(double)))
        return 0;
    tl->capacity = c;
    return 1;
}

static int cell_index(const dem_domain *d, double x, int a)
{
    double c = floor((x - d->def.lo[a]) / d->cell_size[a]);
    if (!(c >= 0.0)) return 0;
    if (c >= d->ncell[a]) return d->ncell[a] - 1;
    return (int)c;
}

/* Visit (count or fill) the cells near triangle t of mesh m. */
static int64_t bin_triangle(dem_domain *d, mesh_wall *m, int64_t t, double reach, int fill)
{
    const double *v[3] = {m->x + 3 * m->tri[3 * t], m->x + 3 * m->tri[3 * t + 1], m->x + 3 * m->tri[3 * t + 2]};
    int c0[3], c1[3];
    double half2 = 0.0;
    for (int a = 0; a < 3; a++) {
        double lo = fmin(v[0][a], fmin(v[1][a], v[2][a])) - reach, hi = fmax(v[0][a], fmax(v[1][a], v[2][a])) + reach;
        if (hi < d->def.lo[a] || lo > d->def.hi[a]) return 0; /* entirely outside the domain */
        c0[a] = cell_index(d, lo, a);
        c1[a] = cell_index(d, hi, a);
        half2 += 0.25 * d->cell_size[a] * d->cell_size[a];
    }
    const double lim = reach + sqrt(half2);
    int64_t added = 0;
    for (int cz = c0[2]; cz <= c1[2]; cz++)
        for (int cy = c0[1]; cy <= c1[1]; cy++)
            for (int cx = c0[0]; cx <= c1[0]; cx++) {
                double centre[3] = {d->def.lo[0] + (cx + 0.5) * d->cell_size[0], d->def.lo[1] + (cy + 0.5) * d->cell_size[1],
                                    d->def.lo[2] + (cz + 0.5) * d->cell_size[2]}, q[3];
                tri_closest_point(centre, v[0], v[1], v[2], q);
                if (tri_dist2(centre, q) > lim * lim) continue;
                int64_t c = ((int64_t)cz * d->ncell[1] + cy) * d->ncell[0] + cx;
                if (fill) m->bin_tri[d->cursor[c]++] = (int32_t)t;
                else m->bin_start[c + 1]++;
                added++;
            }
    return added;
}

/* Bin the triangles of m within reach + margin of each cell, at the vertices' current place. */
static dem_status bin_mesh(dem_domain *d, mesh_wall *m, double reach, double margin)
{
    const double r = reach + margin;
    m->bin_reach = 0.0; /* not valid until done */
    int32_t *st = dem_realloc_array(m->bin_start, (size_t)d->n_cells + 1, sizeof *st);
    double *xb = m->x_binned ? m->x_binned : dem_malloc((size_t)m->nv * 3 * sizeof(double));
    if (st) m->bin_start = st;
    if (xb) m->x_binned = xb;
    if (!st || !xb) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory for the mesh bins");
    memset(st, 0, (size_t)(d->n_cells + 1) * sizeof *st);
    int64_t total = 0;
    for (int64_t t = 0; t < m->nt; t++) total += bin_triangle(d, m, t, r, 0);
    if (total > INT32_MAX)
        return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: a mesh lies in more than %d (triangle, cell) pairs; "
                        "coarser mesh or larger particles needed", INT32_MAX);
    for (int64_t c = 0; c < d->n_cells; c++) st[c + 1] += st[c];
    if (total > m->bin_capacity) {
        int32_t *bt = dem_realloc_array(m->bin_tri, (size_t)grown(total), sizeof *bt);
        if (!bt) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory for the mesh bins");
        m->bin_tri = bt;
        m->bin_capacity = grown(total);
    }
    for (int64_t c = 0; c <= d->n_cells; c++) d->cursor[c] = st[c]; /* the cursor holds >= n_cells + 1 */
    for (int64_t t = 0; t < m->nt; t++) bin_triangle(d, m, t, r, 1);
    memcpy(m->x_binned, m->x, (size_t)m->nv * 3 * sizeof(double));
    for (int a = 0; a < 3; a++) m->bin_ncell[a] = d->ncell[a];
    m->bin_reach = reach;
    m->bin_margin = margin;
    return DEM_OK;
}

/* Whether m's bins still list every triangle within reach of each cell: same grid and reach,
 * and no vertex farther than the margin from where it was binned (a triangle's points move
 * no farther than its vertices). */
static int bins_valid(const dem_domain *d, const mesh_wall *m, double reach)
{
    if (!m->bin_start || m->bin_reach != reach) return 0;
    for (int a = 0; a < 3; a++)
        if (m->bin_ncell[a] != d->ncell[a]) return 0;
    const double margin2 = m->bin_margin * m->bin_margin;
    for (int64_t v = 0; v < m->nv; v++)
        if (tri_dist2(m->x + 3 * v, m->x_binned + 3 * v) > margin2) return 0;
    return 1;
}

/* Copy entry q of the old list into entry k of the new one. */
static void carry_entry(const tri_list *old, int64_t q, tri_list *tl, int64_t k)
{
    tl->active[k] = old->active[q];
    memcpy(tl->hist + 6 * k, old->hist + 6 * q, 6 * sizeof(double));
    memcpy(tl->force + 3 * k, old->force + 3 * q, 3 * sizeof(double));
    memcpy(tl->point + 3 * k, old->point + 3 * q, 3 * sizeof(double));
    memcpy(tl->normal + 3 * k, old->normal + 3 * q, 3 * sizeof(double));
}

void dem_tri_entry_clear(tri_list *tl, int64_t k)
{
    tl->active[k] = 0;
    memset(tl->hist + 6 * k, 0, 6 * sizeof(double));
    memset(tl->force + 3 * k, 0, 3 * sizeof(double));
    memset(tl->torque + 3 * k, 0, 3 * sizeof(double));
    memset(tl->point + 3 * k, 0, 3 * sizeof(double));
    memset(tl->normal + 3 * k, 0, 3 * sizeof(double));
}

dem_status dem_mesh_candidates(dem_domain *d)
{
    const int64_t n = d->n;
    tri_list tmp = d->tris_old;
    d->tris_old = d->tris_cur;
    d->tris_cur = tmp;
    tri_list *tl = &d->tris_cur;
    const tri_list *old = &d->tris_old;
    if (!dem_reserve_rows(&tl->start, &tl->start_cap, n)) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory");
    int64_t *start = tl->start;
    start[0] = 0;
    tl->count = 0;
    d->mesh_disp = 0.0;
    if (d->n_meshes == 0) {
        memset(start, 0, (size_t)(n + 1) * sizeof *start);
        tl->n_rows = n;
        return DEM_OK;
    }
    const double skin = d->def.skin, reach = d->r_max + skin;
    for (int mi = 0; mi < d->n_meshes; mi++) {
        mesh_wall *m = &d->meshes[mi];
        if (bins_valid(d, m, reach)) continue;
        /* a moving mesh is binned a skin wider, so that it is rebinned every few builds
         * rather than at each */
        dem_status s = bin_mesh(d, m, reach, m->moving ? skin : 0.0);
        if (s != DEM_OK) return s;
    }
    for (int mi = 0; mi < d->n_meshes; mi++) {
        memcpy(d->meshes[mi].x_build, d->meshes[mi].x, (size_t)d->meshes[mi].nv * 3 * sizeof(double));
        d->meshes[mi].disp = 0.0;
    }

    const int64_t old_rows = old->start ? old->n_rows : 0;
    int64_t count = 0;
    for (int64_t i = 0; i < n; i++) {
        const double *p = d->x + 3 * i;
        const double cut = d->radius[i] + skin;
        const int64_t c = d->cell_of[i];
        for (int mi = 0; mi < d->n_meshes; mi++) {
            const mesh_wall *m = &d->meshes[mi];
            for (int64_t s = m->bin_start[c]; s < m->bin_start[c + 1]; s++) {
                const int32_t t = m->bin_tri[s], *tv = m->tri + 3 * t;
                const double *a = m->x + 3 * tv[0], *tn = m->normal + 3 * t;
                const double hp = tri_plane_height(p, a, tn);
                if (fabs(hp) >= cut * (1.0 + 1e-9)) continue; /* farther from its plane: no need to look closer
                                                               * (the margin covers the round-off of hp) */
                double q[3];
                tri_closest_point(p, a, m->x + 3 * tv[1], m->x + 3 * tv[2], q);
                const double dist2 = tri_dist2(p, q);
                if (dist2 >= cut * cut) continue;
                if (!tri_list_reserve(tl, count + 1)) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory");
                tl->mesh[count] = mi;
                tl->tri[count] = t;
                dem_tri_entry_clear(tl, count);
                tl->gap[count] = sqrt(dist2) - d->radius[i];
                int32_t oi = d->perm[i];
                if (oi < old_rows)
                    for (int64_t k = old->start[oi]; k < old->start[oi + 1]; k++)
                        if (old->mesh[k] == tl->mesh[count] && old->tri[k] == t) {
                            carry_entry(old, k, tl, count);
                            break;
                        }
                count++;
            }
        }
        start[i + 1] = count;
    }
    tl->count = count;
    tl->n_rows = n;
    return DEM_OK;
}
