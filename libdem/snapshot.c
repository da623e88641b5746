/* HDF5 snapshots that restart a run bit-for-bit (layout: docs/snapshot.md).
 *
 * Why a restart can be exact: the summation order of the forces depends on the particle
 * order and on the Verlet list, which is a function of the positions at the last list build.
 * The snapshot keeps the particles in internal order together with those build positions (of
 * particles and of moving meshes); the reader rebuilds the list from them — the same list,
 * the same order — then puts back the current state, the forces of the last step (the next
 * step's first half kick uses them) and every contact history. */
#include "internal.h"
#include <stdlib.h>
#include <string.h>

dem_status dem_domain_set_seed(dem_domain *d, uint64_t seed)
{
    if (!d) return DEM_ERR_NULL;
    d->seed = seed;
    return DEM_OK;
}

uint64_t dem_domain_seed(const dem_domain *d) { return d ? d->seed : 0; }

#ifdef DEM_NO_HDF5 /* a build without HDF5 (make HDF5=0): snapshots are not available */
dem_status dem_snapshot_write(dem_domain *d, const char *path)
{
    (void)path;
    if (!d) return DEM_ERR_NULL;
    return dem_fail(d, DEM_ERR_UNSUPPORTED, "dem_snapshot_write: this libdem was built without HDF5 (make HDF5=0)");
}
#else
#include "snapshot_h5.h"

/* ---- small HDF5 helpers: 0 on failure --------------------------------------------- */
static int w_dset(hid_t loc, const char *name, hid_t type, hsize_t rows, hsize_t cols, const void *data)
{
    hsize_t dims[2] = {rows, cols};
    hid_t sp = H5Screate_simple(cols ? 2 : 1, dims, NULL);
    if (sp < 0) return 0;
    /* one chunk with a Fletcher-32 checksum: a flipped bit in the data fails the read instead of
     * restarting from a different state (an empty dataset has nothing to check) */
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (dcpl < 0) {
        H5Sclose(sp);
        return 0;
    }
    if (rows > 0 && (H5Pset_chunk(dcpl, cols ? 2 : 1, dims) < 0 || H5Pset_fletcher32(dcpl) < 0)) {
        H5Pclose(dcpl);
        H5Sclose(sp);
        return 0;
    }
    hid_t ds = H5Dcreate2(loc, name, type, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    int ok = ds >= 0 && (rows == 0 || H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0);
    if (ds >= 0) H5Dclose(ds);
    H5Pclose(dcpl);
    H5Sclose(sp);
    return ok;
}

static int w_attr(hid_t loc, const char *name, hid_t type, hsize_t n, const void *data)
{
    hid_t sp = H5Screate_simple(1, &n, NULL);
    if (sp < 0) return 0;
    hid_t at = H5Acreate2(loc, name, type, sp, H5P_DEFAULT, H5P_DEFAULT);
    int ok = at >= 0 && H5Awrite(at, type, data) >= 0;
    if (at >= 0) H5Aclose(at);
    H5Sclose(sp);
    return ok;
}

static int w_attr_str(hid_t loc, const char *name, const char *s)
{
    hid_t ty = H5Tcopy(H5T_C_S1);
    H5Tset_size(ty, strlen(s) + 1);
    hid_t sp = H5Screate(H5S_SCALAR);
    hid_t at = H5Acreate2(loc, name, ty, sp, H5P_DEFAULT, H5P_DEFAULT);
    int ok = at >= 0 && H5Awrite(at, ty, s) >= 0;
    if (at >= 0) H5Aclose(at);
    H5Sclose(sp);
    H5Tclose(ty);
    return ok;
}

/* ---- writing ------------------------------------------------------------------------ */
static int write_settings(hid_t f, const dem_domain *d)
{
    const dem_domain_def *g = &d->def;
    int32_t periodic[3] = {g->periodic[0], g->periodic[1], g->periodic[2]}, nt = g->num_threads;
    int32_t fv = FORMAT_VERSION;
    int64_t next_id = d->next_id;
    return w_attr_str(f, "format", FORMAT_NAME) && w_attr(f, "format_version", H5T_NATIVE_INT32, 1, &fv) &&
           w_attr_str(f, "library_version", DEM_VERSION_STRING) && w_attr(f, "step", H5T_NATIVE_INT64, 1, &d->step) &&
           w_attr(f, "time", H5T_NATIVE_DOUBLE, 1, &d->time) && w_attr(f, "seed", H5T_NATIVE_UINT64, 1, &d->seed) &&
           w_attr(f, "next_id", H5T_NATIVE_INT64, 1, &next_id) && w_attr(f, "lo", H5T_NATIVE_DOUBLE, 3, g->lo) &&
           w_attr(f, "hi", H5T_NATIVE_DOUBLE, 3, g->hi) && w_attr(f, "periodic", H5T_NATIVE_INT32, 3, periodic) &&
           w_attr(f, "gravity", H5T_NATIVE_DOUBLE, 3, g->gravity) && w_attr(f, "dt", H5T_NATIVE_DOUBLE, 1, &g->dt) &&
           w_attr(f, "skin", H5T_NATIVE_DOUBLE, 1, &g->skin) && w_attr(f, "num_threads", H5T_NATIVE_INT32, 1, &nt) &&
           w_attr(f, "max_overlap_ratio", H5T_NATIVE_DOUBLE, 1, &g->max_overlap_ratio) &&
           w_attr(f, "insert_overlap_ratio", H5T_NATIVE_DOUBLE, 1, &g->insert_overlap_ratio) &&
           w_attr(f, "reference_velocity", H5T_NATIVE_DOUBLE, 1, &g->reference_velocity) &&
           w_attr(f, "mesh_displacement", H5T_NATIVE_DOUBLE, 1, &d->mesh_disp);
}

static int write_materials(hid_t f, const dem_domain *d)
{
    const int nm = d->n_materials;
    const size_t np = (size_t)nm * nm;
    hid_t g = H5Gcreate2(f, "materials", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) return 0;
    double *buf = dem_malloc((np > (size_t)nm ? np : (size_t)nm) * 5 * sizeof(double) + 8);
    int32_t *ibuf = dem_malloc(np * sizeof(int32_t) + 4);
    int ok = buf && ibuf;
    static const char *const field[4] = {"youngs_modulus", "poisson_ratio", "density", "shear_modulus"};
    for (int k = 0; ok && k < 4; k++) {
        for (int m = 0; m < nm; m++) {
            const dem_material_def *md = &d->materials[m];
            buf[m] = k == 0 ? md->youngs_modulus : k == 1 ? md->poisson_ratio : k == 2 ? md->density : md->shear_modulus;
        }
        ok = w_dset(g, field[k], H5T_NATIVE_DOUBLE, (hsize_t)nm, 0, buf);
    }
    /* pair table: restitution, friction, rolling_friction, rolling_damping per (a, b); model separately */
    for (size_t p = 0; ok && p < np; p++) {
        const dem_pair_def *pd = &d->pairs[p].def;
        buf[4 * p] = pd->restitution;
        buf[4 * p + 1] = pd->friction;
        buf[4 * p + 2] = pd->rolling_friction;
        buf[4 * p + 3] = pd->rolling_damping;
        ibuf[p] = (int32_t)pd->rolling_model;
    }
    ok = ok && w_dset(g, "pairs", H5T_NATIVE_DOUBLE, np, 4, buf) && w_dset(g, "pair_rolling_model", H5T_NATIVE_INT32, np, 0, ibuf);
    /* effects: rows (a, b, effect index) + parameters; effect names as an attribute */
    int64_t ne = 0;
    for (size_t p = 0; p < np; p++) ne += d->pairs[p].n_effects;
    int32_t *eidx = dem_malloc((size_t)ne * 3 * sizeof(int32_t) + 4);
    double *epar = dem_malloc((size_t)ne * DEM_MAX_EFFECT_PARAMS * sizeof(double) + 8);
    ok = ok && eidx && epar;
    int64_t r = 0;
    for (size_t p = 0; ok && p < np; p++)
        for (int k = 0; k < d->pairs[p].n_effects; k++, r++) {
            eidx[3 * r] = (int32_t)(p / (size_t)nm);
            eidx[3 * r + 1] = (int32_t)(p % (size_t)nm);
            eidx[3 * r + 2] = d->pairs[p].effects[k].effect;
            memcpy(epar + DEM_MAX_EFFECT_PARAMS * r, d->pairs[p].effects[k].params, DEM_MAX_EFFECT_PARAMS * sizeof(double));
        }
    ok = ok && w_dset(g, "effect_pairs", H5T_NATIVE_INT32, (hsize_t)ne, 3, eidx) &&
         w_dset(g, "effect_params", H5T_NATIVE_DOUBLE, (hsize_t)ne, DEM_MAX_EFFECT_PARAMS, epar);
    char names[1024] = "";
    for (int e = 0; e < dem_effect_count(); e++) {
        if (e) strncat(names, ",", sizeof names - strlen(names) - 1);
        strncat(names, dem_effect_get(e)->name, sizeof names - strlen(names) - 1);
    }
    ok = ok && w_attr_str(g, "effect_names", names);
    dem_free(buf);
    dem_free(ibuf);
    dem_free(eidx);
    dem_free(epar);
    H5Gclose(g);
    return ok;
}

static int write_particles(hid_t f, const dem_domain *d)
{
    hid_t g = H5Gcreate2(f, "particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) return 0;
    const hsize_t n = (hsize_t)d->n;
    int ok = w_dset(g, "id", H5T_NATIVE_INT64, n, 0, d->id) && w_dset(g, "material", H5T_NATIVE_INT32, n, 0, d->mat) &&
             w_dset(g, "radius", H5T_NATIVE_DOUBLE, n, 0, d->radius) &&
             w_dset(g, "position", H5T_NATIVE_DOUBLE, n, 3, d->x) && w_dset(g, "velocity", H5T_NATIVE_DOUBLE, n, 3, d->v) &&
             w_dset(g, "angular_velocity", H5T_NATIVE_DOUBLE, n, 3, d->w) &&
             w_dset(g, "force", H5T_NATIVE_DOUBLE, n, 3, d->f) && w_dset(g, "torque", H5T_NATIVE_DOUBLE, n, 3, d->t) &&
             w_dset(g, "position_at_list_build", H5T_NATIVE_DOUBLE, n, 3, d->x_build);
    H5Gclose(g);
    return ok;
}

static int write_walls(hid_t f, const dem_domain *d)
{
    hid_t g = H5Gcreate2(f, "walls", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) return 0;
    const int nw = d->n_walls;
    int32_t *iv = dem_malloc((size_t)(nw + 1) * 3 * sizeof(int32_t));
    double *dv = dem_malloc((size_t)(nw + 1) * 4 * sizeof(double));
    int ok = iv && dv;
    for (int w = 0; ok && w < nw; w++) {
        const dem_plane_wall_def *p = &d->walls[w].def;
        iv[3 * w] = p->axis;
        iv[3 * w + 1] = p->side;
        iv[3 * w + 2] = p->material.index;
        dv[4 * w] = p->position;
        memcpy(dv + 4 * w + 1, p->velocity, 3 * sizeof(double));
    }
    ok = ok && w_dset(g, "plane_axis_side_material", H5T_NATIVE_INT32, (hsize_t)nw, 3, iv) &&
         w_dset(g, "plane_position_velocity", H5T_NATIVE_DOUBLE, (hsize_t)nw, 4, dv);
    int32_t nm = d->n_meshes;
    ok = ok && w_attr(g, "mesh_count", H5T_NATIVE_INT32, 1, &nm);
    for (int k = 0; ok && k < d->n_meshes; k++) {
        const mesh_wall *m = &d->meshes[k];
        char name[32];
        snprintf(name, sizeof name, "mesh_%d", k);
        hid_t mg = H5Gcreate2(g, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (mg < 0) {
            ok = 0;
            break;
        }
        int32_t ints[4] = {m->material, m->servo_on, m->servo_primed, 0};
        int64_t counts[2] = {m->skipped_degenerate, m->input_triangles};
        const dem_servo_def *s = &m->servo;
        double servo[9] = {s->direction[0], s->direction[1], s->direction[2], s->target_force, s->target_stress,
                           s->area, s->max_speed, s->proportional_band, s->filter_time};
        ok = w_dset(mg, "vertices_reference", H5T_NATIVE_DOUBLE, (hsize_t)m->nv, 3, m->x_ref) &&
             w_dset(mg, "triangles", H5T_NATIVE_INT32, (hsize_t)m->nt, 3, m->tri) &&
             w_dset(mg, "vertices", H5T_NATIVE_DOUBLE, (hsize_t)m->nv, 3, m->x) &&
             w_dset(mg, "vertices_at_list_build", H5T_NATIVE_DOUBLE, (hsize_t)m->nv, 3, m->x_build) &&
             w_attr(mg, "material_servo_on_primed", H5T_NATIVE_INT32, 4, ints) &&
             w_attr(mg, "skipped_degenerate_input_triangles", H5T_NATIVE_INT64, 2, counts) &&
             w_attr(mg, "rotation", H5T_NATIVE_DOUBLE, 9, m->rot) && w_attr(mg, "translation", H5T_NATIVE_DOUBLE, 3, m->trans) &&
             w_attr(mg, "centre", H5T_NATIVE_DOUBLE, 3, m->centre) && w_attr(mg, "velocity", H5T_NATIVE_DOUBLE, 3, m->velocity) &&
             w_attr(mg, "angular_velocity", H5T_NATIVE_DOUBLE, 3, m->omega) &&
             w_attr(mg, "servo", H5T_NATIVE_DOUBLE, 9, servo) &&
             w_attr(mg, "servo_force", H5T_NATIVE_DOUBLE, 1, &m->servo_force);
        H5Gclose(mg);
    }
    dem_free(iv);
    dem_free(dv);
    H5Gclose(g);
    return ok;
}

static int nonzero(const double *v, int n)
{
    for (int k = 0; k < n; k++)
        if (v[k] != 0.0) return 1;
    return 0;
}

/* Contact histories keyed by particle ids (pairs: row particle first), only non-zero ones. */
static int write_contacts(hid_t f, const dem_domain *d)
{
    hid_t g = H5Gcreate2(f, "contacts", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) return 0;
    const pair_list *pl = &d->pairs_cur;
    const wall_list *wl = &d->walls_cur;
    const tri_list *tl = &d->tris_cur;
    contact_field pf[PAIR_FIELDS], wf[PLANE_FIELDS], mf[MESH_FIELDS];
    const int pw = pair_fields(d, pf), ww = plane_fields(d, wf), mw = mesh_fields(d, mf);
    const int width = contact_row_width(pw, ww, mw);
    int64_t cap = pl->count + wl->count + tl->count + 1;
    int64_t *ids = dem_malloc((size_t)cap * 2 * sizeof(int64_t));
    int32_t *iv = dem_malloc((size_t)cap * 3 * sizeof(int32_t));
    double *h = dem_malloc((size_t)cap * (size_t)width * sizeof(double));
    int ok = ids && iv && h;
    int64_t r = 0;
    for (int64_t i = 0; ok && i < d->n; i++)
        for (int64_t k = pl->start[i]; k < pl->start[i + 1]; k++)
            if (pl->active[k] || nonzero(pl->hist + 6 * k, 6)) {
                ids[2 * r] = d->id[i];
                ids[2 * r + 1] = d->id[pl->j[k]];
                iv[r] = pl->active[k];
                pack_fields(pf, PAIR_FIELDS, k, h + (int64_t)pw * r);
                r++;
            }
    ok = ok && w_dset(g, "pair_ids", H5T_NATIVE_INT64, (hsize_t)r, 2, ids) &&
         w_dset(g, "pair_active", H5T_NATIVE_INT32, (hsize_t)r, 0, iv) &&
         w_dset(g, "pair_history_reaction", H5T_NATIVE_DOUBLE, (hsize_t)r, (hsize_t)pw, h);
    r = 0;
    for (int64_t i = 0; ok && i < d->n; i++)
        for (int64_t k = wl->start[i]; k < wl->start[i + 1]; k++)
            if (nonzero(wl->hist + 6 * k, 6) || nonzero(wl->force + 3 * k, 3)) {
                ids[r] = d->id[i];
                iv[r] = wl->wall[k];
                pack_fields(wf, PLANE_FIELDS, k, h + (int64_t)ww * r);
                r++;
            }
    ok = ok && w_dset(g, "plane_ids", H5T_NATIVE_INT64, (hsize_t)r, 0, ids) &&
         w_dset(g, "plane_wall", H5T_NATIVE_INT32, (hsize_t)r, 0, iv) &&
         w_dset(g, "plane_history_force", H5T_NATIVE_DOUBLE, (hsize_t)r, (hsize_t)ww, h);
    r = 0;
    for (int64_t i = 0; ok && i < d->n; i++)
        for (int64_t k = tl->start[i]; k < tl->start[i + 1]; k++)
            if (tl->active[k] || nonzero(tl->hist + 6 * k, 6)) {
                ids[r] = d->id[i];
                iv[3 * r] = tl->mesh[k];
                iv[3 * r + 1] = tl->tri[k];
                iv[3 * r + 2] = tl->active[k];
                pack_fields(mf, MESH_FIELDS, k, h + (int64_t)mw * r);
                r++;
            }
    ok = ok && w_dset(g, "mesh_ids", H5T_NATIVE_INT64, (hsize_t)r, 0, ids) &&
         w_dset(g, "mesh_mesh_triangle_active", H5T_NATIVE_INT32, (hsize_t)r, 3, iv) &&
         w_dset(g, "mesh_history_force_point_normal", H5T_NATIVE_DOUBLE, (hsize_t)r, (hsize_t)mw, h);
    dem_free(ids);
    dem_free(iv);
    dem_free(h);
    H5Gclose(g);
    return ok;
}

dem_status dem_snapshot_write(dem_domain *d, const char *path)
{
    if (!d) return DEM_ERR_NULL;
    if (!path) return dem_fail(d, DEM_ERR_NULL, "dem_snapshot_write: path must not be NULL");
    if (d->n > 0 && (d->need_rebuild || !d->forces_valid)) {
        dem_status s = dem_domain_step(d, 0);
        if (s < 0) return s;
    }
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* errors are reported as statuses, not printed */
    /* file format of HDF5 1.10+: object headers carry checksums, and with them the attributes and the
     * index of each single-chunk dataset (1.8's chunk B-tree had none: docs/snapshot.md, Integrity) */
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl < 0 || H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_LATEST) < 0) {
        if (fapl >= 0) H5Pclose(fapl);
        return dem_fail(d, DEM_ERR_IO, "dem_snapshot_write: HDF5 file properties failed");
    }
    hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    if (f < 0) return dem_fail(d, DEM_ERR_IO, "dem_snapshot_write: cannot create '%s'", path);
    int ok = write_settings(f, d) && write_materials(f, d) && write_particles(f, d) && write_walls(f, d) &&
             write_contacts(f, d);
    ok = H5Fclose(f) >= 0 && ok;
    if (!ok) return dem_fail(d, DEM_ERR_IO, "dem_snapshot_write: writing '%s' failed (disk full or not writable?)", path);
    dem_clear_error(d);
    return DEM_OK;
}
#endif /* DEM_NO_HDF5 */
