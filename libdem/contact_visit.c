/* One way to visit a particle's contacts in the three lists (contact_lists.h), for the readers
 * of the current state: the per-contact output (contacts.c), the Love-Weber stress (stress.c)
 * and the diagnostics (diagnostics.c). Each gets the raw geometry, so it keeps its own
 * arithmetic (and its results to the last bit). */
#include "internal.h"
#include <math.h>

void dem_visit_contacts(const dem_domain *d, int64_t i, int mode, contact_visitor fn, void *ctx)
{
    const pair_list *pl = &d->pairs_cur;
    const wall_list *wl = &d->walls_cur;
    const tri_list *tl = &d->tris_cur;
    const double *xi = d->x + 3 * i;
    contact_view c;
    c.i = i;
    for (int64_t k = pl->start ? pl->start[i] : 0; pl->start && k < pl->start[i + 1]; k++) {
        if (mode == VISIT_EVALUATED && !pl->active[k]) continue;
        c.overlap = dem_pair_separation(d, i, k, c.n, &c.dist);
        if (c.overlap <= 0.0) continue;
        c.kind = DEM_CONTACT_PARTICLE;
        c.k = k;
        c.j = pl->j[k];
        c.partner_material = d->mat[c.j];
        c.point = NULL;
        c.force = d->slot + 6 * k;
        fn(d, &c, ctx);
    }
    for (int64_t k = wl->start ? wl->start[i] : 0; wl->start && k < wl->start[i + 1]; k++) {
        const plane_wall *pw = &d->walls[wl->wall[k]];
        c.dist = (xi[pw->def.axis] - pw->def.position) * pw->def.side;
        if (c.dist >= d->radius[i]) continue;
        c.overlap = d->radius[i] - c.dist;
        c.kind = DEM_CONTACT_PLANE;
        c.k = k;
        c.j = -1;
        c.partner_material = pw->def.material.index;
        for (int a = 0; a < 3; a++) c.n[a] = pw->normal[a];
        c.point = NULL;
        c.force = wl->force + 3 * k;
        fn(d, &c, ctx);
    }
    for (int64_t k = tl->start ? tl->start[i] : 0; tl->start && k < tl->start[i + 1]; k++) {
        if (!tl->active[k]) continue; /* mesh contacts exist only as evaluated (selected) */
        const double *q = tl->point + 3 * k;
        double u2 = 0.0;
        for (int a = 0; a < 3; a++) u2 += (xi[a] - q[a]) * (xi[a] - q[a]);
        c.dist = sqrt(u2);
        c.overlap = d->radius[i] - c.dist;
        if (c.overlap <= 0.0 && mode == VISIT_GEOMETRIC) continue;
        c.kind = DEM_CONTACT_MESH;
        c.k = k;
        c.j = -1;
        c.partner_material = d->meshes[tl->mesh[k]].material;
        for (int a = 0; a < 3; a++) c.n[a] = tl->normal[3 * k + a];
        c.point = q;
        c.force = tl->force + 3 * k;
        fn(d, &c, ctx);
    }
}
