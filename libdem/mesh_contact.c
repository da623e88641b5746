/* Sphere–mesh contacts: one contact per genuine touching point.
 *
 * Each candidate triangle gives its closest point q to the sphere centre p and the feature q
 * lies on (face, edge, vertex). A touching triangle whose closest point is on an edge or
 * vertex is kept only if no other touching triangle that contains the same edge or vertex is
 * closer (by more than a round-off tolerance): then q is a local minimum of the distance over
 * the surface, i.e. a real contact, not the rim of a face the sphere is already resting on.
 * Contacts of one mesh at the same feature or within a round-off distance are merged. So a
 * sphere on a flat region feels exactly the plane, whether above a face, an edge or a vertex
 * shared by six triangles; at a convex edge or corner it feels the edge or corner once.
 *
 * Friction history lives in the (particle, triangle) entry; when a contact passes from one
 * triangle to its neighbour (sliding across a seam), the new entry takes the history of the
 * entry that just lost its contact, if their normals agree within 60 degrees. */
#include "contact_law.h"
#include "pair_batch.h"
#include "triangle.h"
#include <math.h>
#include <string.h>

#define MAX_TOUCHING 64
enum { FEATURE_FACE, FEATURE_EDGE, FEATURE_VERTEX };

typedef struct touch {
    int64_t k;       /* list entry */
    double q[3];     /* closest point */
    double dist;     /* |p - q| */
    int kind;        /* FEATURE_* */
    int32_t feature; /* triangle, edge or vertex id within the mesh */
    int accepted;
} touch;

static int contains_feature(const mesh_wall *m, int32_t tri, int kind, int32_t id)
{
    const int32_t *ids = kind == FEATURE_EDGE ? m->tri_edge + 3 * tri : m->tri + 3 * tri;
    return ids[0] == id || ids[1] == id || ids[2] == id;
}

/* The touching entries of particle i; returns their number, or -1 if more than fit. */
static int find_touching(const dem_domain *d, int64_t i, touch *tc)
{
    const tri_list *tl = &d->tris_cur;
    const double *p = d->x + 3 * i, r = d->radius[i];
    /* the distance to a triangle shrinks at most by the particle's and the triangle's
     * displacements since the build: an entry whose gap then exceeds both cannot touch (the
     * margin, far above round-off, keeps the skip from deciding a case the test below would) */
    const double moved = sqrt(tri_dist2(p, d->x_build + 3 * i)) + 1e-6 * r;
    int nt = 0;
    for (int64_t k = tl->start[i]; k < tl->start[i + 1]; k++) {
        const mesh_wall *m = &d->meshes[tl->mesh[k]];
        if (tl->gap[k] - m->disp > moved) continue;
        const int32_t t = tl->tri[k], *tv = m->tri + 3 * t;
        const double *a = m->x + 3 * tv[0], *tn = m->normal + 3 * t;
        const double hp = tri_plane_height(p, a, tn);
        if (hp >= r || hp <= -r) continue; /* farther from the plane than r: cannot touch */
        double q[3];
        int region = tri_closest_point(p, a, m->x + 3 * tv[1], m->x + 3 * tv[2], q);
        double d2 = tri_dist2(p, q);
        if (d2 >= r * r) continue;
        if (nt == MAX_TOUCHING) return -1;
        touch *c = &tc[nt++];
        c->k = k;
        memcpy(c->q, q, sizeof q);
        c->dist = sqrt(d2);
        if (region == TRI_FACE) {
            c->kind = FEATURE_FACE;
            c->feature = t;
        } else if (region <= TRI_EDGE_CA) {
            c->kind = FEATURE_EDGE;
            c->feature = m->tri_edge[3 * t + region - TRI_EDGE_AB];
        } else {
            c->kind = FEATURE_VERTEX;
            c->feature = tv[region - TRI_VERT_A];
        }
        c->accepted = 1;
    }
    return nt;
}

/* Keep the local minima of the distance, merge duplicates (see the file comment). */
static void select_contacts(const dem_domain *d, double r, touch *tc, int nt)
{
    const tri_list *tl = &d->tris_cur;
    const double tol_d = 1e-10 * r;       /* distances equal within round-off */
    const double tol_p = 2e-5 * r;        /* >= sqrt(2 r tol_d): points this close are one contact */
    for (int a = 0; a < nt; a++) {
        if (tc[a].kind == FEATURE_FACE) continue;
        const int ma = tl->mesh[tc[a].k];
        for (int b = 0; b < nt && tc[a].accepted; b++)
            if (b != a && tl->mesh[tc[b].k] == ma && tc[b].dist < tc[a].dist - tol_d &&
                contains_feature(&d->meshes[ma], tl->tri[tc[b].k], tc[a].kind, tc[a].feature))
                tc[a].accepted = 0;
    }
    for (int a = 0; a < nt; a++) {
        if (!tc[a].accepted) continue;
        for (int b = 0; b < a && tc[a].accepted; b++) {
            if (!tc[b].accepted || tl->mesh[tc[b].k] != tl->mesh[tc[a].k]) continue;
            int same = (tc[a].kind == tc[b].kind && tc[a].feature == tc[b].feature) || tri_dist2(tc[a].q, tc[b].q) < tol_p * tol_p;
            if (!same) continue;
            if (tl->active[tc[a].k] && !tl->active[tc[b].k]) tc[b].accepted = 0; /* keep the one with history */
            else tc[a].accepted = 0;
        }
    }
}

/* Does entry k carry one of the accepted contacts? (nt is small: a handful at most) */
static int is_accepted(const touch *tc, int nt, int64_t k)
{
    for (int a = 0; a < nt; a++)
        if (tc[a].accepted && tc[a].k == k) return 1;
    return 0;
}

/* The batched contacts' law, results into their entries. */
static void flush(dem_domain *d, pair_batch *b, double dt_hist)
{
    if (b->m == 0) return;
    dem_pair_batch_props(b, NULL);
    dem_wall_batch_law(b, dt_hist);
    tri_list *tl = &d->tris_cur;
    for (int q = 0; q < b->m; q++) {
        const int64_t k = b->k[q];
        for (int a = 0; a < 3; a++) {
            tl->hist[6 * k + a] = b->h[a][q];
            tl->hist[6 * k + 3 + a] = b->h[3 + a][q];
            tl->force[3 * k + a] = b->force[a][q];
            tl->torque[3 * k + a] = b->ti[a][q];
        }
    }
    b->m = 0;
}

/* Particle i's contacts: found, selected, histories handed over; each goes into the batch b. */
static void particle_contacts(dem_domain *d, int64_t i, double dt_hist, pair_batch *b, int64_t *bad)
{
    tri_list *tl = &d->tris_cur;
    const int64_t k0 = tl->start[i], k1 = tl->start[i + 1];
    const double *p = d->x + 3 * i, *vi = d->v + 3 * i, *wi = d->w + 3 * i, r = d->radius[i];
    touch tc[MAX_TOUCHING];
    int nt = find_touching(d, i, tc);
    if (nt < 0) {
        if (i < *bad) *bad = i;
        return;
    }
    select_contacts(d, r, tc, nt);

    const pair_props *row_pairs = d->pairs + (size_t)d->mat[i] * d->n_materials;
    for (int a = 0; a < nt; a++) {
        if (!tc[a].accepted) continue;
        const int64_t k = tc[a].k;
        const mesh_wall *m = &d->meshes[tl->mesh[k]];
        double n[3]; /* from the surface point to the centre */
        const double inv = tc[a].dist > 1e-12 * r ? 1.0 / tc[a].dist : 0.0;
        for (int c = 0; c < 3; c++) n[c] = (p[c] - tc[a].q[c]) * inv;
        if (inv == 0.0) memcpy(n, m->normal + 3 * tl->tri[k], sizeof n); /* centre on the surface */
        if (!tl->active[k]) { /* new here: take over a contact that just left */
            int64_t best = -1;
            double best_dot = 0.5;
            for (int64_t o = k0; o < k1; o++) {
                if (!tl->active[o] || tl->mesh[o] != tl->mesh[k] || is_accepted(tc, nt, o)) continue;
                const double *no = tl->normal + 3 * o;
                double dot = no[0] * n[0] + no[1] * n[1] + no[2] * n[2];
                if (dot > best_dot) {
                    best_dot = dot;
                    best = o;
                }
            }
            if (best >= 0) {
                memcpy(tl->hist + 6 * k, tl->hist + 6 * best, 6 * sizeof(double));
                dem_tri_entry_clear(tl, best);
            }
        }
        const double *q = tc[a].q, *om = m->omega; /* surface velocity v + w x (q - c) */
        double rel[3] = {q[0] - m->centre[0], q[1] - m->centre[1], q[2] - m->centre[2]};
        double vw[3] = {m->velocity[0] + om[1] * rel[2] - om[2] * rel[1], m->velocity[1] + om[2] * rel[0] - om[0] * rel[2],
                        m->velocity[2] + om[0] * rel[1] - om[1] * rel[0]};
        for (int c = 0; c < 3; c++) {
            tl->point[3 * k + c] = q[c];
            tl->normal[3 * k + c] = n[c];
        }
        tl->active[k] = 1;
        if (r - tc[a].dist > d->def.max_overlap_ratio * r && i < *bad) *bad = i;
        if (b->m == DEM_PAIR_BATCH) flush(d, b, dt_hist);
        const int e = b->m++;
        b->k[e] = k;
        b->pp[e] = &row_pairs[m->material];
        b->dx[e] = n[0];
        b->dy[e] = n[1];
        b->dz[e] = n[2];
        b->dist[e] = tc[a].dist;
        b->ri[e] = r;
        b->imi[e] = d->inv_mass[i];
        for (int c = 0; c < 3; c++) {
            b->dv[c][e] = vi[c] - vw[c];
            b->wi[c][e] = wi[c];
            b->wj[c][e] = om[c];
        }
        for (int c = 0; c < 6; c++) b->h[c][e] = tl->hist[6 * k + c];
    }
    /* entries without a contact now forget theirs */
    for (int64_t k = k0; k < k1; k++)
        if (tl->active[k] && !is_accepted(tc, nt, k)) dem_tri_entry_clear(tl, k);
}

void dem_mesh_contacts_rows(dem_domain *d, int64_t i0, int64_t i1, double dt_hist, pair_batch *scratch, int64_t *bad)
{
    const int64_t *start = d->tris_cur.start;
    scratch->m = 0;
    for (int64_t i = i0; i < i1; i++)
        if (start[i] < start[i + 1]) particle_contacts(d, i, dt_hist, scratch, bad);
    flush(d, scratch, dt_hist);
}

int dem_mesh_scratch_reserve(dem_domain *d)
{
    const int need = d->n_meshes > 0 ? d->def.num_threads : 0;
    if (need <= d->mesh_scratch_threads) return 1;
    void *p = dem_realloc_array(d->mesh_scratch, (size_t)need, sizeof(pair_batch));
    if (!p) return 0;
    d->mesh_scratch = p;
    d->mesh_scratch_threads = need;
    return 1;
}

/* In entry order, as the contacts were once added one by one: the same sums. */
void dem_mesh_contacts_add(const dem_domain *d, int64_t i, double *f, double *t)
{
    const tri_list *tl = &d->tris_cur;
    for (int64_t k = tl->start[i]; k < tl->start[i + 1]; k++) {
        if (!tl->active[k]) continue;
        for (int a = 0; a < 3; a++) {
            f[a] += tl->force[3 * k + a];
            t[a] += tl->torque[3 * k + a];
        }
    }
}

/* Cold path: why particle i was flagged by dem_mesh_contacts_rows. */
dem_status dem_report_runaway_mesh(dem_domain *d, int64_t i)
{
    touch tc[MAX_TOUCHING];
    int nt = find_touching(d, i, tc);
    if (nt < 0)
        return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP,
                        "step %lld: more than %d mesh triangles touch particle id %lld (radius %g m): the mesh is far "
                        "finer than the particles, or the particle went through it",
                        (long long)d->step + 1, MAX_TOUCHING, (long long)d->id[i], d->radius[i]);
    int mesh = nt > 0 ? d->tris_cur.mesh[tc[0].k] : -1;
    return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP,
                    "runaway overlap during step %lld: particle id %lld overlaps mesh wall %d by more than %g of its "
                    "radius (time step too large for the stiffness and speeds, or a wall moved into the particles too "
                    "fast)",
                    (long long)d->step + 1, (long long)d->id[i], mesh, d->def.max_overlap_ratio);
}
