/* Contact forces. Each row i of the half Verlet list is handled by one thread: it sums the
 * forces on i itself and stores the reaction on j per entry; the reactions are gathered
 * later per particle in a fixed order (dem_forces_gather). No atomics, no thread-dependent
 * summation order: results are bitwise identical for any thread count. */
#include "contact_law.h"
#include <math.h>

static const double image_sign[27][3] = {
    {-1, -1, -1}, {0, -1, -1}, {1, -1, -1}, {-1, 0, -1}, {0, 0, -1}, {1, 0, -1}, {-1, 1, -1}, {0, 1, -1}, {1, 1, -1},
    {-1, -1, 0},  {0, -1, 0},  {1, -1, 0},  {-1, 0, 0},  {0, 0, 0},  {1, 0, 0},  {-1, 1, 0},  {0, 1, 0},  {1, 1, 0},
    {-1, -1, 1},  {0, -1, 1},  {1, -1, 1},  {-1, 0, 1},  {0, 0, 1},  {1, 0, 1},  {-1, 1, 1},  {0, 1, 1},  {1, 1, 1}};

/* Cold path: name the contact of row particle i whose overlap exceeds the limit. */
static dem_status report_runaway(dem_domain *d, int64_t i, double (*shift)[3])
{
    const pair_list *pl = &d->pairs_cur;
    const wall_list *wl = &d->walls_cur;
    const double ratio = d->def.max_overlap_ratio, ri = d->radius[i];
    const char *why = "(time step too large for the stiffness and speeds, or particles inserted into each other)";
    for (int64_t k = pl->start[i]; k < pl->start[i + 1]; k++) {
        int32_t j = pl->j[k];
        double r2 = 0;
        for (int a = 0; a < 3; a++) {
            double u = d->x[3 * i + a] - d->x[3 * j + a] - shift[pl->image[k]][a];
            r2 += u * u;
        }
        double delta = ri + d->radius[j] - sqrt(r2), rmin = ri < d->radius[j] ? ri : d->radius[j];
        if (delta > ratio * rmin)
            return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP,
                            "runaway overlap during step %lld: particles id %lld and id %lld overlap by %g m, %.2f of "
                            "the smaller radius (limit %g) %s",
                            (long long)d->step + 1, (long long)d->id[i], (long long)d->id[j], delta, delta / rmin,
                            ratio, why);
    }
    for (int64_t k = wl->start[i]; k < wl->start[i + 1]; k++) {
        const plane_wall *pw = &d->walls[wl->wall[k]];
        double delta = ri - (d->x[3 * i + pw->def.axis] - pw->def.position) * pw->def.side;
        if (delta > ratio * ri)
            return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP,
                            "runaway overlap during step %lld: particle id %lld overlaps plane wall %d by %g m, %.2f "
                            "of its radius (limit %g) %s",
                            (long long)d->step + 1, (long long)d->id[i], wl->wall[k], delta, delta / ri, ratio, why);
    }
    return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP, "runaway overlap during step %lld at particle id %lld %s",
                    (long long)d->step + 1, (long long)d->id[i], why);
}

/* dt_hist: time increment for the spring histories (0 for a force refresh without motion). */
dem_status dem_forces_compute(dem_domain *d, double dt_hist)
{
    const int64_t n = d->n;
    const int nt = d->def.num_threads;
    const pair_list *pl = &d->pairs_cur;
    const wall_list *wl = &d->walls_cur;
    const double *x = d->x, *v = d->v, *w = d->w, *rad = d->radius, *im = d->inv_mass;
    const int32_t *mat = d->mat;
    const int nm = d->n_materials;
    const pair_props *pairs = d->pairs;
    double *pf = d->pair_force, *ptj = d->pair_torque_j;
    double shift[27][3];
    for (int s = 0; s < 27; s++)
        for (int a = 0; a < 3; a++) shift[s][a] = image_sign[s][a] * (d->def.hi[a] - d->def.lo[a]);
    const double ratio = d->def.max_overlap_ratio;
    int64_t bad = INT64_MAX;

#pragma omp parallel for schedule(static) num_threads(nt) reduction(min : bad)
    for (int64_t i = 0; i < n; i++) {
        const double *xi_ = x + 3 * i, *vi = v + 3 * i, *wi = w + 3 * i;
        const double ri = rad[i], imi = im[i];
        const pair_props *row_pairs = pairs + (size_t)mat[i] * nm;
        double fi[3] = {0, 0, 0}, ti[3] = {0, 0, 0};
        for (int64_t k = pl->start[i]; k < pl->start[i + 1]; k++) {
            const int32_t j = pl->j[k];
            const double *sh = shift[pl->image[k]];
            const double dx = xi_[0] - (x[3 * j] + sh[0]);
            const double dy = xi_[1] - (x[3 * j + 1] + sh[1]);
            const double dz = xi_[2] - (x[3 * j + 2] + sh[2]);
            const double rj = rad[j];
            const double rsum = ri + rj;
            const double r2 = dx * dx + dy * dy + dz * dz;
            double *xi = pl->xi + 3 * k, *mr = pl->mr + 3 * k;
            if (r2 >= rsum * rsum) {
                xi[0] = xi[1] = xi[2] = 0.0; /* contact lost: forget the springs */
                mr[0] = mr[1] = mr[2] = 0.0;
                pf[3 * k] = pf[3 * k + 1] = pf[3 * k + 2] = 0.0;
                ptj[3 * k] = ptj[3 * k + 1] = ptj[3 * k + 2] = 0.0;
                continue;
            }
            const double r = sqrt(r2);
            const double inv_r = 1.0 / r;
            contact_in c;
            c.n[0] = dx * inv_r;
            c.n[1] = dy * inv_r;
            c.n[2] = dz * inv_r;
            c.overlap = rsum - r;
            if (c.overlap > ratio * (ri < rj ? ri : rj) && i < bad) bad = i;
            c.distance = r;
            const double ci = ri - 0.5 * c.overlap, cj = rj - 0.5 * c.overlap; /* lever arms */
            const double *vj = v + 3 * j, *wj = w + 3 * j;
            const double sw[3] = {ci * wi[0] + cj * wj[0], ci * wi[1] + cj * wj[1], ci * wi[2] + cj * wj[2]};
            c.vc[0] = vi[0] - vj[0] - (sw[1] * c.n[2] - sw[2] * c.n[1]);
            c.vc[1] = vi[1] - vj[1] - (sw[2] * c.n[0] - sw[0] * c.n[2]);
            c.vc[2] = vi[2] - vj[2] - (sw[0] * c.n[1] - sw[1] * c.n[0]);
            c.wrel[0] = wi[0] - wj[0];
            c.wrel[1] = wi[1] - wj[1];
            c.wrel[2] = wi[2] - wj[2];
            c.r_eff = ri * rj / rsum;
            c.m_eff = 1.0 / (imi + im[j]);
            c.radius_i = ri;
            c.radius_j = rj;
            c.inv_mass_i = imi;
            c.inv_mass_j = im[j];
            contact_out o;
            contact_law(&row_pairs[mat[j]], &c, dt_hist, xi, mr, &o);
            fi[0] += o.force[0];
            fi[1] += o.force[1];
            fi[2] += o.force[2];
            ti[0] += -ci * o.cross[0] + o.mr[0];
            ti[1] += -ci * o.cross[1] + o.mr[1];
            ti[2] += -ci * o.cross[2] + o.mr[2];
            pf[3 * k] = -o.force[0];
            pf[3 * k + 1] = -o.force[1];
            pf[3 * k + 2] = -o.force[2];
            ptj[3 * k] = -cj * o.cross[0] - o.mr[0];
            ptj[3 * k + 1] = -cj * o.cross[1] - o.mr[1];
            ptj[3 * k + 2] = -cj * o.cross[2] - o.mr[2];
        }
        /* plane walls */
        for (int64_t k = wl->start[i]; k < wl->start[i + 1]; k++) {
            const plane_wall *pw = &d->walls[wl->wall[k]];
            const double dist = (xi_[pw->def.axis] - pw->def.position) * pw->def.side;
            double *hxi = wl->xi + 3 * k, *hmr = wl->mr + 3 * k, *wf = wl->force + 3 * k;
            if (dist >= ri) {
                hxi[0] = hxi[1] = hxi[2] = hmr[0] = hmr[1] = hmr[2] = 0.0;
                wf[0] = wf[1] = wf[2] = 0.0;
                continue;
            }
            contact_in c;
            c.n[0] = pw->normal[0];
            c.n[1] = pw->normal[1];
            c.n[2] = pw->normal[2];
            c.overlap = ri - dist;
            if (c.overlap > ratio * ri && i < bad) bad = i;
            c.distance = dist;
            const double ci = ri - 0.5 * c.overlap;
            const double *vw = pw->def.velocity;
            c.vc[0] = vi[0] - vw[0] - ci * (wi[1] * c.n[2] - wi[2] * c.n[1]);
            c.vc[1] = vi[1] - vw[1] - ci * (wi[2] * c.n[0] - wi[0] * c.n[2]);
            c.vc[2] = vi[2] - vw[2] - ci * (wi[0] * c.n[1] - wi[1] * c.n[0]);
            c.wrel[0] = wi[0];
            c.wrel[1] = wi[1];
            c.wrel[2] = wi[2];
            c.r_eff = ri;
            c.m_eff = 1.0 / imi;
            c.radius_i = ri;
            c.radius_j = 0.0;
            c.inv_mass_i = imi;
            c.inv_mass_j = 0.0;
            contact_out o;
            contact_law(&row_pairs[pw->def.material], &c, dt_hist, hxi, hmr, &o);
            fi[0] += o.force[0];
            fi[1] += o.force[1];
            fi[2] += o.force[2];
            ti[0] += -ci * o.cross[0] + o.mr[0];
            ti[1] += -ci * o.cross[1] + o.mr[1];
            ti[2] += -ci * o.cross[2] + o.mr[2];
            wf[0] = o.force[0];
            wf[1] = o.force[1];
            wf[2] = o.force[2];
        }
        double *f = d->f + 3 * i, *t = d->t + 3 * i;
        f[0] = fi[0];
        f[1] = fi[1];
        f[2] = fi[2];
        t[0] = ti[0];
        t[1] = ti[1];
        t[2] = ti[2];
    }
    if (bad != INT64_MAX) return report_runaway(d, bad, shift);
    return DEM_OK;
}

/* Adds the reactions stored on the list entries where i is the j partner, in entry order. */
void dem_forces_gather(const dem_domain *d, int64_t i, double *f, double *t)
{
    const int64_t *te = d->trans_entry;
    for (int64_t q = d->trans_start[i]; q < d->trans_start[i + 1]; q++) {
        const int64_t k = te[q];
        f[0] += d->pair_force[3 * k];
        f[1] += d->pair_force[3 * k + 1];
        f[2] += d->pair_force[3 * k + 2];
        t[0] += d->pair_torque_j[3 * k];
        t[1] += d->pair_torque_j[3 * k + 1];
        t[2] += d->pair_torque_j[3 * k + 2];
    }
}
