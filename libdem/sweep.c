/* The force sweep: pair contact forces, force gathering and the Verlet kicks/drift in one
 * pass over the particles, so each particle's data is used while it is still in cache.
 *
 * The half Verlet list pairs particle i (its row) with partners j that come later in memory
 * order (the forward half of the cell stencil), except across periodic faces. Processing rows
 * in order, particle p's forces are therefore complete once row p is done: its own row gives
 * the i-side, and every entry naming p as partner was in an earlier row, whose reaction waits
 * in its reaction sum, kept in its force and torque arrays (the old forces are not needed once
 * the step is open; the sweep zeroes them first). p is then finished once the batch holding the
 * end of its row is scattered (rows go in batches of entries) — reactions added,
 * walls added, closing half kick, opening half kick and drift — and nothing later reads its old
 * state. Such particles, named only by earlier rows of the same thread, are "direct".
 * The others — named by a later row (periodic wrap) or by another thread's rows, where the sum
 * cannot be built as rows come (two threads would add, or the force arrays hold the parked row
 * sums) — are "deferred": finished after all rows are done, their reactions read back from the
 * per-entry slots. Either way every force is summed in the same order — reactions in list
 * order from zero, subtracted from the own-row sum (list order), then walls — whatever the
 * thread count, so results are bitwise identical for any number of threads, and for any
 * split of the rows among them. That freedom balances the load: the split moves after each
 * sweep toward equal measured row times (rows with mesh walls or dense packing cost more
 * than others), and the deferred particles — each thread's first layer — are finished by
 * all threads in equal shares after the barrier. */
#include "contact_law.h"
#include "pair_batch.h"
#include "sweep.h"
#include <float.h>
#include <math.h>
#ifdef _OPENMP
#include <omp.h>
#endif

/* Rows whose mesh contacts are evaluated together (before the first of them is finished: a
 * particle's position and velocities do not change before its finish, nor the meshes in a
 * sweep); enough contacts to fill the batches in the rigs. */
#define MESH_ROWS 64

/* The sweep's context; each thread works from its own copy (see sweep_view in sweep.h). */
typedef struct sweep_ctx {
    dem_domain *d;
    sweep_view s;
    double *hist;     /* the pair list's springs and activity flags */
    uint8_t *active;
    uint8_t *is_direct;
    const int64_t *wall_start, *tri_start; /* the plane-wall and mesh contact lists' rows */
    const int64_t *trans_start;
    const int32_t *trans_entry;
    double dt_hist;   /* spring history increment (0: refresh without motion) */
    sweep_mode mode;
    int all_slots;    /* write every touching entry's slot (else only those a deferred finish reads) */
    double shift[27][3];
    int periodic;     /* any periodic axis: partners may be images */
    const pair_props *all_pairs; /* the pair type of every contact (one particle material), or NULL */
} sweep_ctx;

/* Gathers the contacts among list entries [k0, k1) (the first in row `row`) into the batch,
 * and the row of each (minus `row`) into row_of; an entry whose spheres no longer touch
 * forgets its springs and clears its slot once.
 * Two passes: the distance test writes every entry's geometry at the next free batch place
 * and advances it only for touching pairs (branch-free: whether a pair touches is a coin
 * toss the branch predictor loses), then the touching ones get the rest of their data. The
 * first pass runs over the entries, not rows then entries: the end of a row (0 to ~10
 * entries) is unpredictable too. */
static void gather(const sweep_ctx *c, int64_t row, int64_t k0, int64_t k1, pair_batch *b, int32_t *row_of)
{
    dem_domain *d = c->d;
    pair_list *pl = &d->pairs_cur;
    /* locals, so that the stores below do not make the compiler reload the list and state
     * pointers from the domain at every entry */
    const double *restrict x = d->x, *restrict v = d->v, *restrict w = d->w;
    const double *restrict rad = d->radius, *restrict im = d->inv_mass;
    const int32_t *restrict pj = pl->j, *restrict mat = d->mat, *restrict entry_row = d->entry_row;
    const uint8_t *restrict image = pl->image;
    uint8_t *restrict active = pl->active;
    double *restrict hist = pl->hist, *restrict slot = d->slot;
    const pair_props *pairs = d->pairs;
    const int n_mat = d->n_materials;
    const int periodic = c->periodic;
    int m = 0, lost = 0;
    int64_t lost_k[DEM_PAIR_BATCH]; /* entries that stopped touching */
    for (int64_t k = k0; k < k1; k++) {
        const int32_t i = entry_row[k], j = pj[k];
        const double ri = rad[i];
        double xj0 = x[3 * j], xj1 = x[3 * j + 1], xj2 = x[3 * j + 2];
        if (periodic) { /* the partner's periodic image (a zero shift elsewhere) */
            const double *sh = c->shift[image[k]];
            xj0 += sh[0];
            xj1 += sh[1];
            xj2 += sh[2];
        }
        const double dx = x[3 * i] - xj0, dy = x[3 * i + 1] - xj1, dz = x[3 * i + 2] - xj2;
        const double rj = rad[j], rsum = ri + rj;
        const double r2 = dx * dx + dy * dy + dz * dz;
        const int touch = r2 < rsum * rsum;
        b->k[m] = k;
        b->j[m] = j;
        b->dx[m] = dx;
        b->dy[m] = dy;
        b->dz[m] = dz;
        b->r2[m] = r2;
        b->ri[m] = ri;
        b->rj[m] = rj;
        row_of[m] = (int32_t)(i - row);
        m += touch;
        lost_k[lost] = k;
        lost += active[k] > touch; /* active is 0 or 1: it was touching and is no longer */
    }
    for (int q = 0; q < lost; q++) {
        const int64_t k = lost_k[q];
        for (int a = 0; a < 6; a++) hist[6 * k + a] = slot[6 * k + a] = 0.0;
        active[k] = 0;
    }
    const pair_props *all = c->all_pairs;
    for (int q = 0; q < m; q++) {
        const int64_t i = row + row_of[q], k = b->k[q];
        const int32_t j = b->j[q];
        const double *vi = v + 3 * i, *wi = w + 3 * i, *vj = v + 3 * j, *wj = w + 3 * j, *h = hist + 6 * k;
        if (!all) b->pp[q] = &pairs[(size_t)mat[i] * n_mat + mat[j]];
        b->imi[q] = im[i];
        b->imj[q] = im[j];
        for (int a = 0; a < 3; a++) {
            b->dv[a][q] = vi[a] - vj[a];
            b->wi[a][q] = wi[a];
            b->wj[a][q] = wj[a];
        }
        for (int a = 0; a < 6; a++) b->h[a][q] = h[a];
    }
    b->m = m;
    dem_pair_batch_props(b, all);
}

/* Whether particle p is direct for the thread of rows [r0, r1): its own, and named only by
 * rows of it before p (trans_hi is -1 for a particle nobody names). Each sweep stores it for
 * its own rows in is_direct, which the thread then reads (never another thread's part). */
static inline int direct(const dem_domain *d, int64_t p, int64_t r0, int64_t r1)
{
    return p >= r0 && p < r1 && d->trans_lo[p] >= r0 && d->trans_hi[p] < p;
}

/* Contact q of the batch back into the list: springs, reaction slot, activity; its force and
 * torque on i added to its row's sums acc (force 3, torque 3), the reaction to a direct
 * partner's sum. */
static inline void scatter(const sweep_ctx *c, const pair_batch *b, int q, double *acc, int64_t *bad_pair, int64_t r0,
                           int64_t r1)
{
    const sweep_view *s = &c->s;
    const int64_t k = b->k[q];
    const double ri = b->ri[q], rj = b->rj[q];
    if (b->overlap[q] > s->max_overlap_ratio * (ri < rj ? ri : rj) && k < *bad_pair) *bad_pair = k;
    double *h = c->hist + 6 * k;
    for (int a = 0; a < 6; a++) h[a] = b->h[a][q];
    c->active[k] = 1;
    for (int a = 0; a < 3; a++) {
        acc[a] += b->force[a][q];
        acc[3 + a] += b->ti[a][q];
    }
    const int32_t j = b->j[q];
    const int j_direct = j >= r0 && j < r1 && c->is_direct[j];
    if (j_direct) {
        double *fj = s->f + 3 * (int64_t)j, *tj = s->t + 3 * (int64_t)j;
        for (int a = 0; a < 3; a++) {
            fj[a] += b->force[a][q];
            tj[a] += b->tj[a][q];
        }
    }
    if (!j_direct || c->all_slots) {
        double *sl = s->slot + 6 * k;
        for (int a = 0; a < 3; a++) {
            sl[a] = b->force[a][q];
            sl[3 + a] = b->tj[a][q];
        }
    }
}

/* Opening half kick and drift of particle p (inlined into the sweep; dem_open_step() for the
 * first step of a call). */
static inline void open_step(const sweep_view *s, int64_t p, const double *f, const double *t, double *vl, double *wl,
                             sweep_result *res)
{
    const double dt = s->dt, half = s->half, *g = s->gravity, *lo = s->lo, *hi = s->hi;
    const double imp = s->inv_mass[p], iip = s->inv_inertia[p];
    double *xp = s->x + 3 * p;
    const double *xb = s->x_build + 3 * p;
    double disp2 = 0.0, sum = 0.0;
    int in = 1;
    for (int a = 0; a < 3; a++) {
        vl[a] += half * (f[a] * imp + g[a]);
        wl[a] += half * t[a] * iip;
        xp[a] += dt * vl[a];
        const double u = xp[a] - xb[a];
        disp2 += u * u;
        sum += xp[a] + wl[a];
        in &= (xp[a] >= lo[a]) & (xp[a] <= hi[a]);
    }
    if (disp2 > res->maxdisp2) res->maxdisp2 = disp2;
    if (!(sum - sum == 0.0)) { /* NaN or inf somewhere in x, v (through x) or w */
        if (p < res->bad_nan) res->bad_nan = p;
    } else if (!in && p < res->bad_out) {
        res->bad_out = p;
    }
}

void dem_open_step(const sweep_view *s, int64_t p, const double *f, const double *t, double *vl, double *wl,
                   sweep_result *res)
{
    open_step(s, p, f, t, vl, wl, res);
}

/* Finish particle p: add its reactions (summed in list order: as summed during the sweep if
 * it is direct, else from its slots) and walls to its row sums f, t, store the forces, then
 * the kicks and drift the mode asks for. */
static inline void finish(const sweep_ctx *c, int64_t p, double *f, double *t, sweep_result *res, int is_direct)
{
    const sweep_view *s = &c->s;
    double r[6] = {0, 0, 0, 0, 0, 0};
    if (is_direct) {
        for (int a = 0; a < 3; a++) {
            r[a] = s->f[3 * p + a];
            r[3 + a] = s->t[3 * p + a];
        }
    } else {
        const int32_t *te = c->trans_entry;
        for (int64_t q = c->trans_start[p]; q < c->trans_start[p + 1]; q++) {
            const double *sl = s->slot + 6 * (int64_t)te[q];
            for (int a = 0; a < 6; a++) r[a] += sl[a];
        }
    }
    for (int a = 0; a < 3; a++) {
        f[a] -= r[a];
        t[a] += r[3 + a];
    }
    if (c->wall_start[p] < c->wall_start[p + 1]) dem_wall_contacts(c->d, p, c->dt_hist, f, t, &res->bad_wall);
    if (c->tri_start[p] < c->tri_start[p + 1]) dem_mesh_contacts_add(c->d, p, f, t);
    double *fp = s->f + 3 * p, *tp = s->t + 3 * p;
    for (int a = 0; a < 3; a++) {
        fp[a] = f[a];
        tp[a] = t[a];
    }
    if (c->mode == SWEEP_FORCES) return;
    const double half = s->half, *g = s->gravity;
    const double imp = s->inv_mass[p], iip = s->inv_inertia[p];
    double *vp = s->v + 3 * p, *wp = s->w + 3 * p;
    double vl[3], wl[3];
    for (int a = 0; a < 3; a++) { /* closing half kick */
        vl[a] = vp[a] + half * (f[a] * imp + g[a]);
        wl[a] = wp[a] + half * t[a] * iip;
    }
    if (c->mode == SWEEP_CLOSE_OPEN) open_step(s, p, f, t, vl, wl, res);
    for (int a = 0; a < 3; a++) {
        vp[a] = vl[a];
        wp[a] = wl[a];
    }
}

void dem_sweep_view(dem_domain *d, sweep_view *s)
{
    s->x = d->x;
    s->v = d->v;
    s->w = d->w;
    s->f = d->f;
    s->t = d->t;
    s->slot = d->slot;
    s->x_build = d->x_build;
    s->inv_mass = d->inv_mass;
    s->inv_inertia = d->inv_inertia;
    s->dt = d->def.dt;
    s->half = 0.5 * d->def.dt;
    s->max_overlap_ratio = d->def.max_overlap_ratio;
    for (int a = 0; a < 3; a++) {
        s->gravity[a] = d->def.gravity[a];
        s->lo[a] = d->def.periodic[a] ? -DBL_MAX : d->def.lo[a];
        s->hi[a] = d->def.periodic[a] ? DBL_MAX : d->def.hi[a];
    }
}

void dem_sweep_result_init(sweep_result *r)
{
    r->maxdisp2 = 0.0;
    r->bad_nan = r->bad_out = r->bad_wall = r->bad_pair = INT64_MAX;
}

/* Phase 1 of a thread's sweep: which of its rows are direct (their reaction sums start at zero
 * in the force arrays) and which deferred (listed in d->deferred from r0); returns the count. */
static int64_t open_rows(dem_domain *d, int64_t r0, int64_t r1)
{
    int64_t n_deferred = 0;
    for (int64_t i = r0; i < r1; i++) {
        d->is_direct[i] = (uint8_t)direct(d, i, r0, r1);
        if (d->is_direct[i])
            for (int a = 0; a < 3; a++) d->f[3 * i + a] = d->t[3 * i + a] = 0.0;
        else
            d->deferred[r0 + n_deferred++] = (int32_t)i;
    }
    return n_deferred;
}

/* Phase 2: rows [r0, r1) in batches of list entries — gather, law, scatter in list order —
 * every row finished (direct) or parked (deferred) once the batch holding its end is done;
 * the mesh contacts of each block of MESH_ROWS rows evaluated before its first row finishes. */
static void sweep_rows(const sweep_ctx *ctx_in, int64_t r0, int64_t r1, int tid, sweep_result *res_out)
{
    /* local copies: through the pointers, every store to a force array could alias the
     * context's doubles (shifts, dt) and the result, and the compiler reloads them */
    const sweep_ctx c = *ctx_in, *ctx = &c;
    sweep_result r = *res_out, *res = &r;
    dem_domain *d = ctx->d;
    const double dt_hist = ctx->dt_hist;
    pair_batch b; /* ~29 KB on the thread's stack */
    /* as much again for the mesh contacts, where there are any: the domain's, reserved by
     * the step (a second batch on the stack slowed the sweep without meshes by ~2 %) */
    const int any_mesh = d->tris_cur.count > 0;
    pair_batch *mesh_batch = any_mesh ? (pair_batch *)d->mesh_scratch + tid : NULL;
    int64_t mesh_done = r0; /* rows before this have their mesh contacts evaluated */
    const int64_t *start = d->pairs_cur.start;
    int64_t row = r0, k = start[r0];
    double acc[DEM_PAIR_BATCH][6]; /* force and torque sums of the batch's rows (from `row`) */
    int32_t row_of[DEM_PAIR_BATCH]; /* the batch's contacts' rows (minus `row`) */
    for (int a = 0; a < 6; a++) acc[0][a] = 0.0;
    while (row < r1) {
        /* a batch: at most DEM_PAIR_BATCH entries, from rows [row, cap) */
        const int64_t cap = r1 - row > DEM_PAIR_BATCH ? row + DEM_PAIR_BATCH : r1;
        const int64_t k1 = start[cap] - k > DEM_PAIR_BATCH ? k + DEM_PAIR_BATCH : start[cap];
        gather(ctx, row, k, k1, &b, row_of);
        dem_pair_batch_law(&b, dt_hist);
        /* rows [row, fin) end in this batch; row fin (if below the cap) goes on in the next */
        int64_t fin = row;
        while (fin < cap && start[fin + 1] <= k1) fin++;
        const int64_t n_acc = fin < cap ? fin - row + 1 : fin - row; /* rows with contacts here */
        for (int64_t r = 1; r < n_acc; r++)
            for (int a = 0; a < 6; a++) acc[r][a] = 0.0;
        /* in list order, so each row's sums are added up as the scalar order has them
         * (one loop over the contacts, not rows then contacts: the end of a row is
         * unpredictable for the branch predictor) */
        for (int q = 0; q < b.m; q++) scatter(ctx, &b, q, acc[row_of[q]], &res->bad_pair, r0, r1);
        for (int64_t o = 0; row < fin; row++, o++) {
            if (any_mesh && row >= mesh_done) { /* the next block's mesh contacts, batched */
                mesh_done = r1 - row > MESH_ROWS ? row + MESH_ROWS : r1;
                dem_mesh_contacts_rows(d, row, mesh_done, dt_hist, mesh_batch, &res->bad_wall);
            }
            double f[3] = {acc[o][0], acc[o][1], acc[o][2]}, t[3] = {acc[o][3], acc[o][4], acc[o][5]};
            /* direct: finish now; else park the row sums in the force arrays and finish
             * after the barrier */
            if (ctx->is_direct[row]) {
                finish(ctx, row, f, t, res, 1);
            } else {
                for (int a = 0; a < 3; a++) {
                    ctx->s.f[3 * row + a] = f[a];
                    ctx->s.t[3 * row + a] = t[a];
                }
            }
        }
        /* the unfinished row's sums so far start the next batch's */
        for (int a = 0; a < 6; a++) acc[0][a] = fin < cap ? acc[n_acc - 1][a] : 0.0;
        k = k1;
    }
    *res_out = r;
}

/* Phase 3, after the barrier: the deferred particles (the first layer of each thread's rows:
 * named by the rows before them) in equal shares among the nth threads, whichever thread's
 * rows they are in (use_split: every thread's list and count known; else each its own). */
static void finish_deferred(const sweep_ctx *ctx, int tid, int nth, int use_split, const int64_t *deferred_count,
                            int64_t n_deferred, int64_t r0, sweep_result *res)
{
    dem_domain *d = ctx->d;
    int64_t total = n_deferred, q0 = 0, q1 = n_deferred;
    if (use_split) {
        total = 0;
        for (int u = 0; u < nth; u++) total += deferred_count[u];
        q0 = total * tid / nth;
        q1 = total * (tid + 1) / nth;
    }
    int64_t base = 0;
    for (int u = use_split ? 0 : tid, last = use_split ? nth - 1 : tid; u <= last; u++) {
        const int64_t count = use_split ? deferred_count[u] : n_deferred, from = use_split ? d->split[u] : r0;
        for (int64_t q = q0 > base ? q0 : base; q < q1 && q < base + count; q++) {
            const int64_t i = d->deferred[from + q - base];
            double f[3] = {d->f[3 * i], d->f[3 * i + 1], d->f[3 * i + 2]};
            double t[3] = {d->t[3 * i], d->t[3 * i + 1], d->t[3 * i + 2]};
            finish(ctx, i, f, t, res, 0);
        }
        base += count;
    }
}

sweep_result dem_sweep(dem_domain *d, double dt_hist, sweep_mode mode)
{
    sweep_ctx c;
    c.d = d;
    c.dt_hist = dt_hist;
    c.mode = mode;
    /* the slots are read by the stress and the snapshots only where the forces belong to the
     * positions, i.e. after the last sweep of a call: the steps before it skip the slots of
     * direct partners (48 bytes per contact and step) */
    c.all_slots = mode != SWEEP_CLOSE_OPEN;
    for (int s = 0; s < 27; s++)
        for (int a = 0; a < 3; a++) c.shift[s][a] = dem_image_sign[s][a] * (d->def.hi[a] - d->def.lo[a]);
    dem_sweep_view(d, &c.s);
    c.hist = d->pairs_cur.hist;
    c.active = d->pairs_cur.active;
    c.is_direct = d->is_direct;
    c.wall_start = d->walls_cur.start;
    c.tri_start = d->tris_cur.start;
    c.trans_start = d->trans_start;
    c.trans_entry = d->trans_entry;
    c.periodic = d->def.periodic[0] || d->def.periodic[1] || d->def.periodic[2];
    /* one particle material (the usual case): one pair type, known without looking */
    const int32_t one = d->single_material;
    c.all_pairs = one >= 0 ? &d->pairs[(size_t)one * d->n_materials + one] : NULL;
    const int64_t n = d->n;
    double maxdisp2 = 0.0;
    int64_t bad_nan = INT64_MAX, bad_out = INT64_MAX, bad_wall = INT64_MAX, bad_pair = INT64_MAX;
    const int team = dem_team(d);
    dem_split_prepare(d, team);
    int balanced = 0;                         /* the team used d->split */
    int64_t deferred_count[DEM_SPLIT_MAX]; /* then: each thread's deferred particles */
#pragma omp parallel num_threads(team) reduction(max : maxdisp2) \
    reduction(min : bad_nan, bad_out, bad_wall, bad_pair)
    {
        int tid = 0, nth = 1;
        double t_start = 0.0;
#ifdef _OPENMP
        tid = omp_get_thread_num();
        nth = omp_get_num_threads();
        t_start = omp_get_wtime();
#endif
        const sweep_ctx ctx = c; /* the thread's own copy: see sweep_view in sweep.h */
        const int use_split = nth == d->split_threads;
        if (tid == 0) balanced = use_split;
        const int64_t r0 = use_split ? d->split[tid] : n * tid / nth, r1 = use_split ? d->split[tid + 1] : n * (tid + 1) / nth;
        sweep_result res;
        dem_sweep_result_init(&res);
        const int64_t n_deferred = open_rows(d, r0, r1);
        if (use_split) deferred_count[tid] = n_deferred;
        sweep_rows(&ctx, r0, r1, tid, &res);
#ifdef _OPENMP
        if (use_split) d->split_busy[tid] = omp_get_wtime() - t_start;
#else
        (void)t_start;
#endif
#pragma omp barrier
        finish_deferred(&ctx, tid, nth, use_split, deferred_count, n_deferred, r0, &res);
        maxdisp2 = res.maxdisp2;
        bad_nan = res.bad_nan;
        bad_out = res.bad_out;
        bad_wall = res.bad_wall;
        bad_pair = res.bad_pair;
    }
    if (balanced && d->split_threads > 1) dem_split_rebalance(d, d->split_threads);
    sweep_result out = {maxdisp2, bad_nan, bad_out, bad_wall, bad_pair};
    return out;
}
