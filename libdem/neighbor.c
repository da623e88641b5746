/* Neighbour search: linked cells -> spatial sort of the particles -> half Verlet list
 * with skin (CSR), wall candidate list, and transfer of the contact histories from the
 * previous list. Everything is deterministic whatever the thread count: counting sort
 * by cell, rows filled in a fixed stencil order, transposed list filled serially. */
#include "internal.h"
#include "cell_grid.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#define IMAGE_NONE 13

/* Periodic image code -> shift of the partner in box lengths: code = (sx+1) + 3(sy+1) + 9(sz+1). */
const double dem_image_sign[27][3] = {
    {-1, -1, -1}, {0, -1, -1}, {1, -1, -1}, {-1, 0, -1}, {0, 0, -1}, {1, 0, -1}, {-1, 1, -1}, {0, 1, -1}, {1, 1, -1},
    {-1, -1, 0},  {0, -1, 0},  {1, -1, 0},  {-1, 0, 0},  {0, 0, 0},  {1, 0, 0},  {-1, 1, 0},  {0, 1, 0},  {1, 1, 0},
    {-1, -1, 1},  {0, -1, 1},  {1, -1, 1},  {-1, 0, 1},  {0, 0, 1},  {1, 0, 1},  {-1, 1, 1},  {0, 1, 1},  {1, 1, 1}};

static int grow(void **p, int64_t *cap, int64_t need, size_t elem)
{
    if (need <= *cap) return 1;
    int64_t c = *cap > 0 ? *cap : 64;
    while (c < need) c *= 2;
    void *q = dem_realloc_array(*p, (size_t)c, elem);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

/* Capacity for `need` entries with a 10 % margin (a settling bed's list grows by little at a
 * time; doubling would waste up to half the memory). */
static int64_t margin(int64_t need) { return need + need / 10 + 256; }

/* Whether a per-entry capacity should change for `need` entries: too small, or more than 40 %
 * above need (a bed that has settled from a loose start keeps its peak capacity otherwise;
 * the hysteresis between 1.1x and 1.4x avoids resizing back and forth). */
static int refit(int64_t need, int64_t capacity) { return need > capacity || capacity > margin(need) + need * 3 / 10; }

/* Fit a pair list's per-entry arrays to hold `need` entries (contents not kept). */
static int pair_list_reserve(pair_list *pl, int64_t need)
{
    if (!refit(need, pl->capacity)) return 1;
    int64_t c = margin(need);
    void **i32[] = {(void **)&pl->j};
    void **u8[] = {(void **)&pl->image, (void **)&pl->active};
    void **hist[] = {(void **)&pl->hist};
    const int ok = dem_realloc_all(i32, 1, (size_t)c, sizeof(int32_t)) & dem_realloc_all(u8, 2, (size_t)c, 1) &
                   dem_realloc_all(hist, 1, (size_t)c * 6, sizeof(double));
    if (!ok && c > pl->capacity) return 0; /* every array still holds the old capacity */
    pl->capacity = c;                      /* (a failed shrink leaves arrays larger than c) */
    return 1;
}

static int wall_list_reserve(wall_list *wl, int64_t need)
{
    if (need <= wl->capacity) return 1;
    int64_t c = margin(need);
    void **i32[] = {(void **)&wl->wall};
    void **vec3[] = {(void **)&wl->force}, **vec6[] = {(void **)&wl->hist};
    if (!dem_realloc_all(i32, 1, (size_t)c, sizeof(int32_t)) || !dem_realloc_all(vec3, 1, (size_t)c * 3, sizeof(double)) ||
        !dem_realloc_all(vec6, 1, (size_t)c * 6, sizeof(double)))
        return 0;
    wl->capacity = c;
    return 1;
}

/* Cells per particle the grid may have. The grid spans the domain; where the particles fill
 * a small part of it (a heap in a wide box, a ring in its bounding box) a tighter cap makes
 * the cells many times the cut-off and the list build tests every pair of far larger cells
 * (2 per particle: aor tiny's cells were 28 cut-off volumes, ~108 distance tests per particle
 * and pass). The cost is memory in such domains: 16 bytes per cell (offsets and the sort's
 * cursor) and 4 per cell and mesh (mesh bins), i.e. at most 128 + 32 x meshes bytes per
 * particle. */
#define CELLS_PER_PARTICLE 8

/* Choose the cell grid: cells at least as large as the cut-off, at most ~CELLS_PER_PARTICLE
 * per particle. */
static dem_status choose_cells(dem_domain *d, int64_t n_live)
{
    const double cutoff = 2.0 * d->r_max + d->def.skin;
    int64_t limit = CELLS_PER_PARTICLE * n_live + 1024;
    for (int a = 0; a < 3; a++) {
        double len = d->def.hi[a] - d->def.lo[a];
        int nc = (int)floor(len / cutoff);
        if (nc < 1) nc = 1;
        if (nc > 1 << 20) nc = 1 << 20;
        if (d->def.periodic[a] && nc < 3)
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT,
                            "periodic axis %d is %g m long; it must be at least 3 x (2 R_max + skin) = %g m", a, len,
                            3 * cutoff);
        d->ncell[a] = nc;
    }
    for (;;) {
        int64_t total = (int64_t)d->ncell[0] * d->ncell[1] * d->ncell[2];
        if (total <= limit) break;
        int a = 0;
        for (int b = 1; b < 3; b++)
            if (d->ncell[b] > d->ncell[a]) a = b;
        int nc = (d->ncell[a] + 1) / 2;
        if (d->def.periodic[a] && nc < 3) nc = 3;
        if (nc == d->ncell[a]) break;
        d->ncell[a] = nc;
    }
    for (int a = 0; a < 3; a++) d->cell_size[a] = (d->def.hi[a] - d->def.lo[a]) / d->ncell[a];
    d->n_cells = (int64_t)d->ncell[0] * d->ncell[1] * d->ncell[2];
    return DEM_OK;
}

static inline int cell_coord(const dem_domain *d, double x, int a)
{
    return cell_clamp(floor((x - d->def.lo[a]) / d->cell_size[a]), d->ncell[a]);
}

/* Permute a particle array (elements of elem_bytes) into the new order. */
static void permute(void *arr, const int32_t *perm, int64_t n, size_t elem_bytes, void *scratch)
{
    char *src = arr, *dst = scratch;
    for (int64_t i = 0; i < n; i++) memcpy(dst + (size_t)i * elem_bytes, src + (size_t)perm[i] * elem_bytes, elem_bytes);
    memcpy(arr, scratch, (size_t)n * elem_bytes);
}

/* The 13 forward neighbour cells (half stencil); the own cell is handled with j > i. */
static const int half_stencil[13][3] = {{1, 0, 0},  {-1, 1, 0}, {0, 1, 0},  {1, 1, 0},  {-1, -1, 1},
                                        {0, -1, 1}, {1, -1, 1}, {-1, 0, 1}, {0, 0, 1},  {1, 0, 1},
                                        {-1, 1, 1}, {0, 1, 1},  {1, 1, 1}};

/* One thread's candidate partners for its rows, found in one pass and then copied into the
 * list (a counting pass first would compute every distance twice). */
typedef struct scan_buffer {
    int32_t *j;
    uint8_t *image;
    int64_t count, cap;
    int failed; /* out of memory */
} scan_buffer;

void dem_neighbor_free_scratch(dem_domain *d)
{
    scan_buffer *b = d->scan;
    for (int p = 0; p < d->n_scan; p++) {
        dem_free(b[p].j);
        dem_free(b[p].image);
    }
    dem_free(d->scan);
    d->scan = NULL;
    d->n_scan = 0;
}

static int scan_buffer_grow(scan_buffer *b)
{
    int64_t c = b->cap ? 2 * b->cap : 1024;
    int32_t *j = dem_realloc_array(b->j, (size_t)c, sizeof *j);
    if (j) b->j = j;
    uint8_t *im = dem_realloc_array(b->image, (size_t)c, 1);
    if (im) b->image = im;
    if (!j || !im) return 0;
    b->cap = c;
    return 1;
}

/* Appends the candidate partners of particle i to b; returns their number (-1: out of memory). */
static int64_t scan_row(const dem_domain *d, int64_t i, scan_buffer *b)
{
    const double *x = d->x;
    const double skin = d->def.skin;
    const double ri = d->radius[i];
    int c[3];
    int64_t cell = d->cell_of[i];
    c[0] = (int)(cell % d->ncell[0]);
    c[1] = (int)((cell / d->ncell[0]) % d->ncell[1]);
    c[2] = (int)(cell / ((int64_t)d->ncell[0] * d->ncell[1]));
    int64_t count = 0;
    /* own cell: later particles */
    for (int64_t j = i + 1; j < d->cell_start[cell + 1]; j++) {
        double dx = x[3 * i] - x[3 * j], dy = x[3 * i + 1] - x[3 * j + 1], dz = x[3 * i + 2] - x[3 * j + 2];
        double cut = ri + d->radius[j] + skin;
        if (dx * dx + dy * dy + dz * dz < cut * cut) {
            if (b->count == b->cap && !scan_buffer_grow(b)) return -1;
            b->j[b->count] = (int32_t)j;
            b->image[b->count++] = IMAGE_NONE;
            count++;
        }
    }
    for (int s = 0; s < 13; s++) {
        int nc[3], sh[3];
        int skip = 0;
        for (int a = 0; a < 3; a++) {
            nc[a] = c[a] + half_stencil[s][a];
            sh[a] = 0;
            if (nc[a] < 0 || nc[a] >= d->ncell[a]) {
                if (!d->def.periodic[a]) {
                    skip = 1;
                    break;
                }
                sh[a] = nc[a] < 0 ? -1 : 1;
                nc[a] -= sh[a] * d->ncell[a];
            }
        }
        if (skip) continue;
        double shift[3];
        for (int a = 0; a < 3; a++) shift[a] = sh[a] * (d->def.hi[a] - d->def.lo[a]);
        int64_t ncell = cell_index(d->ncell, nc[0], nc[1], nc[2]);
        uint8_t image = (uint8_t)((sh[0] + 1) + 3 * (sh[1] + 1) + 9 * (sh[2] + 1));
        for (int64_t j = d->cell_start[ncell]; j < d->cell_start[ncell + 1]; j++) {
            double dx = x[3 * i] - (x[3 * j] + shift[0]);
            double dy = x[3 * i + 1] - (x[3 * j + 1] + shift[1]);
            double dz = x[3 * i + 2] - (x[3 * j + 2] + shift[2]);
            double cut = ri + d->radius[j] + skin;
            if (dx * dx + dy * dy + dz * dz < cut * cut) {
                if (b->count == b->cap && !scan_buffer_grow(b)) return -1;
                b->j[b->count] = (int32_t)j;
                b->image[b->count++] = image;
                count++;
            }
        }
    }
    return count;
}

/* Copy the history of pair (old oa, old ob) into entry k of the new list, or zero it. */
static void transfer_pair_history(const pair_list *old, int64_t old_rows, int32_t oa, int32_t ob, pair_list *pl,
                                  int64_t k)
{
    for (int pass = 0; pass < 2; pass++) {
        int32_t r = pass ? ob : oa, want = pass ? oa : ob;
        if (r < 0 || r >= old_rows) continue;
        for (int64_t q = old->start[r]; q < old->start[r + 1]; q++) {
            if (old->j[q] == want) {
                double sgn = pass ? -1.0 : 1.0; /* the history is seen from the row particle */
                for (int a = 0; a < 6; a++) pl->hist[6 * k + a] = sgn * old->hist[6 * q + a];
                return;
            }
        }
    }
    for (int a = 0; a < 6; a++) pl->hist[6 * k + a] = 0.0;
}

/* The invariants every reader of the lists relies on (checking builds only, DEM_CHECKS): row
 * offsets that rise and fit the arrays, partners that exist and come later in memory unless
 * across a periodic face, ids and indices that map to each other, the transposed index whole. */
static void check_lists(const dem_domain *d)
{
#ifdef DEM_CHECKS
    const pair_list *pl = &d->pairs_cur;
    const wall_list *wl = &d->walls_cur;
    const tri_list *tl = &d->tris_cur;
    DEM_ASSERT(pl->n_rows == d->n && pl->start[0] == 0 && pl->start[d->n] == pl->count && pl->count <= pl->capacity);
    DEM_ASSERT(wl->start[0] == 0 && wl->start[d->n] == wl->count && wl->count <= wl->capacity);
    DEM_ASSERT(tl->start[0] == 0 && tl->start[d->n] == tl->count && tl->count <= tl->capacity);
    for (int64_t i = 0; i < d->n; i++) {
        DEM_ASSERT(pl->start[i] <= pl->start[i + 1] && wl->start[i] <= wl->start[i + 1] && tl->start[i] <= tl->start[i + 1]);
        DEM_ASSERT(d->index_of_id[d->id[i]] == (int32_t)i);
        for (int64_t k = pl->start[i]; k < pl->start[i + 1]; k++)
            DEM_ASSERT(pl->j[k] >= 0 && pl->j[k] < d->n && (pl->j[k] > i || pl->image[k] != 13));
    }
    DEM_ASSERT(d->trans_start[d->n] == pl->count);
#else
    (void)d;
#endif
}

/* ---- the phases of a build ----------------------------------------------------------- */

/* Live particles (not in remove_mask): their count; the largest radius and the one material
 * of them all (-2: several) into the domain. */
static int64_t count_live(dem_domain *d, const unsigned char *remove_mask)
{
    const int64_t n_old = d->n;
    int64_t n = 0;
    double rmax = 0.0;
    int32_t material = -1; /* the one material of every particle, or -2 */
    for (int64_t i = 0; i < n_old; i++) {
        if (remove_mask && remove_mask[i]) continue;
        n++;
        if (d->radius[i] > rmax) rmax = d->radius[i];
        material = material == -1 || material == d->mat[i] ? d->mat[i] : -2;
    }
    d->r_max = rmax;
    d->single_material = material;
    return n;
}

/* Periodic axes: positions back into the box (they drift out by < skin between builds). */
static void wrap_periodic(dem_domain *d)
{
    const int64_t n_old = d->n;
    for (int64_t i = 0; i < n_old; i++)
        for (int a = 0; a < 3; a++)
            if (d->def.periodic[a]) {
                double len = d->def.hi[a] - d->def.lo[a];
                double *xa = &d->x[3 * i + a];
                if (*xa < d->def.lo[a] || *xa >= d->def.hi[a]) {
                    *xa -= floor((*xa - d->def.lo[a]) / len) * len;
                    if (*xa >= d->def.hi[a]) *xa = d->def.lo[a]; /* rounding at the upper edge */
                }
            }

}

/* Counting sort of the live particles by cell (stable, so deterministic): d->perm[new] = old. */
static dem_status sort_by_cell(dem_domain *d, const unsigned char *remove_mask)
{
    const int64_t n_old = d->n;
    int64_t tmp_cap = d->cap_cells;
    if (!grow((void **)&d->cell_start, &tmp_cap, d->n_cells + 1, sizeof *d->cell_start))
        return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory for %lld cells", (long long)d->n_cells);
    d->cap_cells = tmp_cap;
    memset(d->cell_start, 0, (size_t)(d->n_cells + 1) * sizeof *d->cell_start);
    for (int64_t i = 0; i < n_old; i++) {
        if (remove_mask && remove_mask[i]) {
            d->cell_of[i] = -1;
            continue;
        }
        int64_t c = cell_index(d->ncell, cell_coord(d, d->x[3 * i], 0), cell_coord(d, d->x[3 * i + 1], 1),
                               cell_coord(d, d->x[3 * i + 2], 2));
        d->cell_of[i] = (int32_t)c;
        d->cell_start[c + 1]++;
    }
    for (int64_t c = 0; c < d->n_cells; c++) d->cell_start[c + 1] += d->cell_start[c];
    int64_t need_cursor = (d->n_cells > n_old ? d->n_cells : n_old) + 1;
    if (!grow((void **)&d->cursor, &d->cap_cursor, need_cursor, sizeof *d->cursor))
        return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory");
    int64_t *cursor = d->cursor;
    memcpy(cursor, d->cell_start, (size_t)(d->n_cells + 1) * sizeof *cursor);
    for (int64_t i = 0; i < n_old; i++) /* perm[new] = old */
        if (d->cell_of[i] >= 0) d->perm[cursor[d->cell_of[i]]++] = (int32_t)i;

    return DEM_OK;
}

/* The particle arrays into the sorted order (n live particles); cells, id index and the
 * positions at this build follow. */
static void reorder_particles(dem_domain *d, int64_t n)
{
    void *scr = d->f; /* the forces are recomputed after every build: their array is free */
    d->forces_valid = 0;
    permute(d->x, d->perm, n, 3 * sizeof(double), scr);
    permute(d->v, d->perm, n, 3 * sizeof(double), scr);
    permute(d->w, d->perm, n, 3 * sizeof(double), scr);
    permute(d->radius, d->perm, n, sizeof(double), scr);
    permute(d->inv_mass, d->perm, n, sizeof(double), scr);
    permute(d->inv_inertia, d->perm, n, sizeof(double), scr);
    permute(d->mat, d->perm, n, sizeof(int32_t), scr);
    permute(d->id, d->perm, n, sizeof(dem_particle_id), scr);
    d->n = n;
    for (int64_t i = 0; i < n; i++) {
        int64_t c = cell_index(d->ncell, cell_coord(d, d->x[3 * i], 0), cell_coord(d, d->x[3 * i + 1], 1),
                               cell_coord(d, d->x[3 * i + 2], 2));
        d->cell_of[i] = (int32_t)c;
    }
    for (dem_particle_id k = 0; k < d->next_id; k++) d->index_of_id[k] = -1;
    for (int64_t i = 0; i < n; i++) d->index_of_id[d->id[i]] = (int32_t)i;
    memcpy(d->x_build, d->x, (size_t)n * 3 * sizeof(double));

}

/* The pair list: each thread scans its rows into its buffer; prefix; copy + histories from the
 * old list (the buffers stay with the domain: a build at a size seen before allocates nothing). */
static dem_status build_pair_list(dem_domain *d, int64_t n)
{
    const int nt = dem_team(d);
    pair_list *pl = &d->pairs_cur;
    const pair_list *old = &d->pairs_old;
    const int64_t old_rows = old->start ? old->n_rows : 0;
    /* a buffer for every thread the domain may use (the team is at most num_threads), not only
     * the current team's (below) */
    const int most = d->def.num_threads;
    if (d->n_scan < most) {
        scan_buffer *grown = dem_realloc_array(d->scan, (size_t)most, sizeof *grown);
        if (!grown) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory");
        memset(grown + d->n_scan, 0, (size_t)(most - d->n_scan) * sizeof *grown);
        d->scan = grown;
        d->n_scan = most;
    }
    scan_buffer *bufs = d->scan;
    for (int p = 0; p < nt; p++) bufs[p].count = bufs[p].failed = 0;
    if (!dem_reserve_rows(&pl->start, &pl->start_cap, n)) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory");
    int64_t *start = pl->start;
    int parts = 1; /* rows [n p / parts, n (p + 1) / parts) went to buffer p */
#pragma omp parallel num_threads(nt)
    {
        int tid = 0, nth = 1;
#ifdef _OPENMP
        tid = omp_get_thread_num();
        nth = omp_get_num_threads();
#endif
        if (tid == 0) parts = nth;
        scan_buffer *b = &bufs[tid];
        for (int64_t i = n * tid / nth; i < n * (tid + 1) / nth && !b->failed; i++) {
            const int64_t c = scan_row(d, i, b);
            b->failed = c < 0;
            start[i + 1] = c;
        }
    }
    int64_t count = 0;
    int ok = 1;
    for (int p = 0; p < parts; p++) {
        count += bufs[p].count;
        ok &= !bufs[p].failed;
    }
    ok = ok && pair_list_reserve(pl, count);
    /* Every buffer can take the whole list: when the thread governor changes the team (one
     * thread scanning every row, or a thread that scanned none joining), a warm step must not
     * allocate (tests/c/test_no_alloc.c). A failed reserve is no error here: the scan grows a
     * buffer when it needs to. */
    for (int p = 0; ok && p < d->n_scan; p++)
        while (bufs[p].cap < count && scan_buffer_grow(&bufs[p])) {
        }
    if (ok) {
        start[0] = 0;
        for (int64_t i = 0; i < n; i++) start[i + 1] += start[i];
        pl->count = count;
        pl->n_rows = n;
#pragma omp parallel for schedule(static, 1) num_threads(nt)
        for (int p = 0; p < parts; p++) {
            const int64_t k0 = start[n * p / parts];
            if (bufs[p].count > 0) { /* (an empty buffer was never allocated) */
                memcpy(pl->j + k0, bufs[p].j, (size_t)bufs[p].count * sizeof *pl->j);
                memcpy(pl->image + k0, bufs[p].image, (size_t)bufs[p].count);
            }
            for (int64_t i = n * p / parts; i < n * (p + 1) / parts; i++)
                for (int64_t k = start[i]; k < start[i + 1]; k++) {
                    transfer_pair_history(old, old_rows, d->perm[i], d->perm[pl->j[k]], pl, k);
                    pl->active[k] = 1; /* reaction slot not yet written */
                }
        }
    }
    if (!ok) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory for the pair list");

    return DEM_OK;
}

/* Per-entry force scratch and the transposed list (the entries where a particle is j), and
 * which rows name each particle: the sweep's finishing order. */
static dem_status build_transposed(dem_domain *d, int64_t n)
{
    const pair_list *pl = &d->pairs_cur;
    const int64_t count = pl->count, *start = pl->start;
    int64_t *cursor = d->cursor;
    if (refit(count, d->trans_capacity)) {
        int64_t c = margin(count);
        void **slots[] = {(void **)&d->slot};
        void **te[] = {(void **)&d->trans_entry, (void **)&d->entry_row};
        const int ok = dem_realloc_all(slots, 1, (size_t)c * 6, sizeof(double)) &
                       dem_realloc_all(te, 2, (size_t)c, sizeof(int32_t));
        if (!ok && c > d->trans_capacity) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory");
        d->trans_capacity = c;
    }
    /* the histories are carried over: the old list's arrays may follow the new size (it is
     * refilled at the next build; a failed shrink only keeps memory) */
    if (refit(count, d->pairs_old.capacity) && count <= d->pairs_old.capacity) {
        pair_list_reserve(&d->pairs_old, count);
        d->pairs_old.count = 0;
    }
    memset(d->trans_start, 0, (size_t)(n + 1) * sizeof *d->trans_start);
    for (int64_t k = 0; k < count; k++) d->trans_start[pl->j[k] + 1]++;
    for (int64_t i = 0; i < n; i++) d->trans_start[i + 1] += d->trans_start[i];
    memcpy(cursor, d->trans_start, (size_t)(n + 1) * sizeof *cursor);
    for (int64_t k = 0; k < count; k++) d->trans_entry[cursor[pl->j[k]]++] = (int32_t)k; /* entry order */
    for (int64_t i = 0; i < n; i++) {
        d->trans_lo[i] = INT32_MAX;
        d->trans_hi[i] = -1;
    }
    for (int64_t i = 0; i < n; i++) /* which rows name each particle: the sweep's finishing order */
        for (int64_t k = start[i]; k < start[i + 1]; k++) {
            int32_t j = pl->j[k];
            d->entry_row[k] = (int32_t)i;
            if (i < d->trans_lo[j]) d->trans_lo[j] = (int32_t)i;
            if (i > d->trans_hi[j]) d->trans_hi[j] = (int32_t)i;
        }

    return DEM_OK;
}

/* Plane-wall candidates, grouped by particle, with their histories from the old list. */
static dem_status build_wall_list(dem_domain *d, int64_t n)
{
    const int64_t old_rows = d->pairs_old.start ? d->pairs_old.n_rows : 0;
    wall_list *wl = &d->walls_cur;
    const wall_list *wold = &d->walls_old;
    if (!dem_reserve_rows(&wl->start, &wl->start_cap, n)) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory");
    int64_t *wstart = wl->start;
    int64_t wc = 0;
    wstart[0] = 0;
    for (int64_t i = 0; i < n; i++) {
        for (int w = 0; w < d->n_walls; w++) {
            const plane_wall *pw = &d->walls[w];
            double dist = (d->x[3 * i + pw->def.axis] - pw->def.position) * pw->def.side;
            if (dist < d->radius[i] + d->def.skin) {
                if (!wall_list_reserve(wl, wc + 1)) return dem_fail(d, DEM_ERR_NO_MEMORY, "neighbour build: out of memory");
                wl->wall[wc] = w;
                /* history from the old list */
                int32_t oi = d->perm[i];
                double *h = wl->hist + 6 * wc;
                for (int a = 0; a < 6; a++) h[a] = 0.0;
                if (wold->start && oi < old_rows)
                    for (int64_t k = wold->start[oi]; k < wold->start[oi + 1]; k++)
                        if (wold->wall[k] == w) {
                            memcpy(h, wold->hist + 6 * k, 6 * sizeof(double));
                        }
                wl->force[3 * wc] = wl->force[3 * wc + 1] = wl->force[3 * wc + 2] = 0.0;
                wc++;
            }
        }
        wstart[i + 1] = wc;
    }
    wl->count = wc;

    return DEM_OK;
}

dem_status dem_neighbor_rebuild(dem_domain *d, const unsigned char *remove_mask)
{
    const int64_t n = count_live(d, remove_mask);
    dem_status s = choose_cells(d, n);
    if (s != DEM_OK) return s;
    wrap_periodic(d);
    s = sort_by_cell(d, remove_mask);
    if (s != DEM_OK) return s;
    reorder_particles(d, n);
    /* swap the lists: the old one keeps the histories, indexed by old particle index */
    pair_list tp = d->pairs_old;
    d->pairs_old = d->pairs_cur;
    d->pairs_cur = tp;
    wall_list tw = d->walls_old;
    d->walls_old = d->walls_cur;
    d->walls_cur = tw;

    if ((s = build_pair_list(d, n)) != DEM_OK || (s = build_transposed(d, n)) != DEM_OK ||
        (s = build_wall_list(d, n)) != DEM_OK)
        return s;
    s = dem_mesh_candidates(d);
    if (s != DEM_OK) return s;
    check_lists(d);
    d->need_rebuild = 0;
    d->profile.neighbor_builds++;
    return DEM_OK;
}
