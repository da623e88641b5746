/* Reading a snapshot back into a new domain that continues the run bit-for-bit (see
 * snapshot.c for why this works, docs/snapshot.md for the layout). Every missing or
 * inconsistent piece is reported by name as DEM_ERR_FORMAT. */
#ifdef DEM_NO_HDF5 /* a build without HDF5 (make HDF5=0) */
#include "internal.h"
#include <stdio.h>

dem_status dem_snapshot_read(const char *path, dem_domain **out, char *msg, size_t msg_size)
{
    (void)path;
    if (out) *out = NULL;
    if (msg && msg_size) snprintf(msg, msg_size, "dem_snapshot_read: this libdem was built without HDF5 (make HDF5=0)");
    return DEM_ERR_UNSUPPORTED;
}
#else
#include "snapshot_h5.h"
#include <stdlib.h>
#include <string.h>

/* ---- HDF5 reading helpers: 0 on failure --------------------------------------------- */
/* Reads a whole dataset of rows x cols (cols 0: 1-D) after checking its shape. */
static int r_dset(hid_t loc, const char *name, hid_t type, hsize_t rows, hsize_t cols, void *data)
{
    if (H5Lexists(loc, name, H5P_DEFAULT) <= 0) return 0;
    hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
    if (ds < 0) return 0;
    hid_t sp = H5Dget_space(ds);
    hsize_t dims[2] = {0, 0};
    int rank = H5Sget_simple_extent_ndims(sp);
    H5Sget_simple_extent_dims(sp, dims, NULL);
    int ok = rank == (cols ? 2 : 1) && dims[0] == rows && (!cols || dims[1] == cols);
    if (ok && rows > 0) ok = H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
    H5Sclose(sp);
    H5Dclose(ds);
    return ok;
}

/* Number of rows of a dataset, -1 if missing. */
static int64_t r_rows(hid_t loc, const char *name)
{
    if (H5Lexists(loc, name, H5P_DEFAULT) <= 0) return -1;
    hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
    if (ds < 0) return -1;
    hid_t sp = H5Dget_space(ds);
    hsize_t dims[2] = {0, 0};
    H5Sget_simple_extent_dims(sp, dims, NULL);
    H5Sclose(sp);
    H5Dclose(ds);
    return (int64_t)dims[0];
}

static int r_attr(hid_t loc, const char *name, hid_t type, hsize_t n, void *data)
{
    if (H5Aexists(loc, name) <= 0) return 0;
    hid_t at = H5Aopen(loc, name, H5P_DEFAULT);
    if (at < 0) return 0;
    hid_t sp = H5Aget_space(at);
    hssize_t got = H5Sget_simple_extent_npoints(sp);
    int ok = got == (hssize_t)n && H5Aread(at, type, data) >= 0;
    H5Sclose(sp);
    H5Aclose(at);
    return ok;
}

static int r_attr_str(hid_t loc, const char *name, char *buf, size_t size)
{
    if (H5Aexists(loc, name) <= 0) return 0;
    hid_t at = H5Aopen(loc, name, H5P_DEFAULT);
    hid_t ty = H5Aget_type(at);
    size_t n = H5Tget_size(ty);
    int ok = H5Tget_class(ty) == H5T_STRING && n < size && H5Aread(at, ty, buf) >= 0;
    if (ok) buf[n] = '\0';
    H5Tclose(ty);
    H5Aclose(at);
    return ok;
}

typedef struct reader {
    hid_t f;
    char *msg;
    size_t msg_size;
    dem_domain *d;
    const char *path; /* named in every message */
} reader;

static dem_status bad(reader *r, const char *what)
{
    if (r->msg && r->msg_size) snprintf(r->msg, r->msg_size, "dem_snapshot_read: '%s': %s", r->path, what);
    return DEM_ERR_FORMAT;
}

/* Turns a failed library call during reading into a message. */
static dem_status lib_fail(reader *r, dem_status s)
{
    if (r->msg && r->msg_size)
        snprintf(r->msg, r->msg_size, "dem_snapshot_read: '%s': %s", r->path, dem_domain_last_error(r->d));
    return s < 0 ? s : DEM_ERR_FORMAT;
}

static dem_status read_settings(reader *r, dem_domain_def *def, int64_t *step, double *time, uint64_t *seed,
                                int64_t *next_id, double *mesh_disp)
{
    char fmt[64];
    int32_t version, periodic[3], nt;
    if (!r_attr_str(r->f, "format", fmt, sizeof fmt) || strcmp(fmt, FORMAT_NAME) != 0)
        return bad(r, "not a libdem snapshot (attribute 'format' missing or different)");
    if (!r_attr(r->f, "format_version", H5T_NATIVE_INT32, 1, &version) || version != FORMAT_VERSION)
        return bad(r, "unsupported snapshot format version");
    *def = dem_default_domain_def();
    int ok = r_attr(r->f, "step", H5T_NATIVE_INT64, 1, step) && r_attr(r->f, "time", H5T_NATIVE_DOUBLE, 1, time) &&
             r_attr(r->f, "seed", H5T_NATIVE_UINT64, 1, seed) && r_attr(r->f, "next_id", H5T_NATIVE_INT64, 1, next_id) &&
             r_attr(r->f, "lo", H5T_NATIVE_DOUBLE, 3, def->lo) && r_attr(r->f, "hi", H5T_NATIVE_DOUBLE, 3, def->hi) &&
             r_attr(r->f, "periodic", H5T_NATIVE_INT32, 3, periodic) &&
             r_attr(r->f, "gravity", H5T_NATIVE_DOUBLE, 3, def->gravity) && r_attr(r->f, "dt", H5T_NATIVE_DOUBLE, 1, &def->dt) &&
             r_attr(r->f, "skin", H5T_NATIVE_DOUBLE, 1, &def->skin) && r_attr(r->f, "num_threads", H5T_NATIVE_INT32, 1, &nt) &&
             r_attr(r->f, "max_overlap_ratio", H5T_NATIVE_DOUBLE, 1, &def->max_overlap_ratio) &&
             r_attr(r->f, "insert_overlap_ratio", H5T_NATIVE_DOUBLE, 1, &def->insert_overlap_ratio) &&
             r_attr(r->f, "reference_velocity", H5T_NATIVE_DOUBLE, 1, &def->reference_velocity) &&
             r_attr(r->f, "mesh_displacement", H5T_NATIVE_DOUBLE, 1, mesh_disp);
    if (!ok) return bad(r, "domain settings (root attributes) missing or malformed");
    for (int a = 0; a < 3; a++) def->periodic[a] = periodic[a];
    def->num_threads = nt;
    if (*next_id < 0 || *step < 0) return bad(r, "negative step or id counter");
    return DEM_OK;
}

static dem_status read_materials(reader *r)
{
    dem_domain *d = r->d;
    hid_t g = H5Gopen2(r->f, "materials", H5P_DEFAULT);
    if (g < 0) return bad(r, "group 'materials' missing");
    dem_status st = DEM_OK;
    int64_t nm = r_rows(g, "density");
    double *e = NULL, *nu = NULL, *rho = NULL, *gmod = NULL, *pairs = NULL, *epar = NULL;
    int32_t *model = NULL, *eidx = NULL;
    if (nm < 0 || nm > 4096) {
        st = bad(r, "materials/density missing");
        goto out;
    }
    const size_t np = (size_t)nm * (size_t)nm;
    e = dem_malloc((size_t)nm * sizeof *e + 8);
    nu = dem_malloc((size_t)nm * sizeof *nu + 8);
    rho = dem_malloc((size_t)nm * sizeof *rho + 8);
    gmod = dem_calloc((size_t)nm + 1, sizeof *gmod);
    pairs = dem_malloc(np * 4 * sizeof *pairs + 8);
    model = dem_malloc(np * sizeof *model + 4);
    if (!e || !nu || !rho || !gmod || !pairs || !model) {
        st = bad(r, "out of memory");
        goto out;
    }
    if (!r_dset(g, "youngs_modulus", H5T_NATIVE_DOUBLE, (hsize_t)nm, 0, e) ||
        !r_dset(g, "poisson_ratio", H5T_NATIVE_DOUBLE, (hsize_t)nm, 0, nu) ||
        !r_dset(g, "density", H5T_NATIVE_DOUBLE, (hsize_t)nm, 0, rho) || !r_dset(g, "pairs", H5T_NATIVE_DOUBLE, np, 4, pairs) ||
        !r_dset(g, "pair_rolling_model", H5T_NATIVE_INT32, np, 0, model)) {
        st = bad(r, "materials: a dataset is missing or has the wrong shape");
        goto out;
    }
    /* shear_modulus: written since G could be given apart from E and nu; absent: isotropic (0) */
    if (H5Lexists(g, "shear_modulus", H5P_DEFAULT) > 0 && !r_dset(g, "shear_modulus", H5T_NATIVE_DOUBLE, (hsize_t)nm, 0, gmod)) {
        st = bad(r, "materials/shear_modulus has the wrong shape");
        goto out;
    }
    for (int64_t m = 0; m < nm; m++) {
        dem_material_def md = {e[m], nu[m], rho[m], gmod[m]};
        dem_material id;
        dem_status s = dem_material_create(d, &md, &id);
        if (s != DEM_OK) {
            st = lib_fail(r, s);
            goto out;
        }
    }
    for (int64_t a = 0; a < nm; a++)
        for (int64_t b = a; b < nm; b++) {
            const double *p = pairs + 4 * (a * nm + b);
            dem_pair_def pd = {p[0], p[1], p[2], (dem_rolling_model)model[a * nm + b], p[3]};
            dem_status s = dem_pair_set(d, (dem_material){(int32_t)a}, (dem_material){(int32_t)b}, &pd);
            if (s != DEM_OK) {
                st = lib_fail(r, s);
                goto out;
            }
        }
    int64_t ne = r_rows(g, "effect_pairs");
    char names[1024];
    if (ne < 0 || !r_attr_str(g, "effect_names", names, sizeof names)) {
        st = bad(r, "materials: effect tables missing");
        goto out;
    }
    eidx = dem_malloc((size_t)ne * 3 * sizeof *eidx + 4);
    epar = dem_malloc((size_t)ne * DEM_MAX_EFFECT_PARAMS * sizeof *epar + 8);
    if (!eidx || !epar || !r_dset(g, "effect_pairs", H5T_NATIVE_INT32, (hsize_t)ne, 3, eidx) ||
        !r_dset(g, "effect_params", H5T_NATIVE_DOUBLE, (hsize_t)ne, DEM_MAX_EFFECT_PARAMS, epar)) {
        st = bad(r, "materials: effect tables malformed");
        goto out;
    }
    for (int64_t k = 0; k < ne; k++) {
        /* effects are stored by their index in the writer's registry: find the name */
        int want = eidx[3 * k + 2], idx = 0;
        const char *p = names;
        while (idx < want && p && *p) {
            p = strchr(p, ',');
            if (p) p++;
            idx++;
        }
        char name[128] = "";
        if (p && *p) {
            size_t len = strcspn(p, ",");
            if (len >= sizeof name) len = sizeof name - 1;
            memcpy(name, p, len);
            name[len] = '\0';
        }
        int ei = dem_effect_find(name);
        if (ei < 0) {
            st = bad(r, "the snapshot uses an effect this library does not have");
            goto out;
        }
        if (eidx[3 * k] > eidx[3 * k + 1]) continue; /* symmetric: set once */
        dem_status s = dem_pair_set_effect(d, (dem_material){eidx[3 * k]}, (dem_material){eidx[3 * k + 1]}, name, epar + DEM_MAX_EFFECT_PARAMS * k,
                                           dem_effect_get(ei)->n_params);
        if (s != DEM_OK) {
            st = lib_fail(r, s);
            goto out;
        }
    }
out:
    dem_free(e);
    dem_free(nu);
    dem_free(rho);
    dem_free(gmod);
    dem_free(pairs);
    dem_free(model);
    dem_free(eidx);
    dem_free(epar);
    H5Gclose(g);
    return st;
}

static dem_status read_mesh(reader *r, hid_t g, int k)
{
    char name[32];
    snprintf(name, sizeof name, "mesh_%d", k);
    hid_t mg = H5Gopen2(g, name, H5P_DEFAULT);
    if (mg < 0) return bad(r, "a mesh group (walls/mesh_N) is missing");
    mesh_wall m;
    memset(&m, 0, sizeof m);
    dem_status st = DEM_OK;
    m.nv = r_rows(mg, "vertices_reference");
    m.nt = r_rows(mg, "triangles");
    int32_t ints[4];
    int64_t counts[2];
    double servo[9];
    double *xb = NULL;
    if (m.nv < 3 || m.nt < 1 || m.nt > INT32_MAX / 3) {
        st = bad(r, "mesh arrays missing");
        goto out;
    }
    m.x_ref = dem_malloc((size_t)m.nv * 3 * sizeof(double));
    m.tri = dem_malloc((size_t)m.nt * 3 * sizeof(int32_t));
    xb = dem_malloc((size_t)m.nv * 3 * sizeof(double));
    if (!m.x_ref || !m.tri || !xb || !r_dset(mg, "vertices_reference", H5T_NATIVE_DOUBLE, (hsize_t)m.nv, 3, m.x_ref) ||
        !r_dset(mg, "triangles", H5T_NATIVE_INT32, (hsize_t)m.nt, 3, m.tri) ||
        !r_dset(mg, "vertices_at_list_build", H5T_NATIVE_DOUBLE, (hsize_t)m.nv, 3, xb) ||
        !r_attr(mg, "material_servo_on_primed", H5T_NATIVE_INT32, 4, ints) ||
        !r_attr(mg, "skipped_degenerate_input_triangles", H5T_NATIVE_INT64, 2, counts) ||
        !r_attr(mg, "rotation", H5T_NATIVE_DOUBLE, 9, m.rot) || !r_attr(mg, "translation", H5T_NATIVE_DOUBLE, 3, m.trans) ||
        !r_attr(mg, "centre", H5T_NATIVE_DOUBLE, 3, m.centre) || !r_attr(mg, "velocity", H5T_NATIVE_DOUBLE, 3, m.velocity) ||
        !r_attr(mg, "angular_velocity", H5T_NATIVE_DOUBLE, 3, m.omega) || !r_attr(mg, "servo", H5T_NATIVE_DOUBLE, 9, servo) ||
        !r_attr(mg, "servo_force", H5T_NATIVE_DOUBLE, 1, &m.servo_force)) {
        st = bad(r, "a mesh wall's data is missing or has the wrong shape");
        goto out;
    }
    for (int64_t q = 0; q < 3 * m.nt; q++)
        if (m.tri[q] < 0 || m.tri[q] >= m.nv) {
            st = bad(r, "a mesh triangle names a vertex that does not exist");
            goto out;
        }
    if (ints[0] < 0 || ints[0] >= r->d->n_materials) {
        st = bad(r, "a mesh wall names an unknown material");
        goto out;
    }
    double rot[9], trans[3];
    memcpy(rot, m.rot, sizeof rot);
    memcpy(trans, m.trans, sizeof trans);
    if (!dem_mesh_finish(&m)) { /* resets the pose: put it back */
        st = bad(r, "out of memory");
        goto out;
    }
    memcpy(m.rot, rot, sizeof rot);
    memcpy(m.trans, trans, sizeof trans);
    dem_mesh_update_world(&m);
    memcpy(m.x_build, xb, (size_t)m.nv * 3 * sizeof(double));
    m.material = ints[0];
    m.servo_on = ints[1];
    m.servo_primed = ints[2];
    m.skipped_degenerate = counts[0];
    m.input_triangles = counts[1];
    dem_servo_def *s = &m.servo;
    memcpy(s->direction, servo, 3 * sizeof(double));
    s->target_force = servo[3];
    s->target_stress = servo[4];
    s->area = servo[5];
    s->max_speed = servo[6];
    s->proportional_band = servo[7];
    s->filter_time = servo[8];
    m.moving = m.servo_on;
    for (int a = 0; a < 3; a++) m.moving |= (m.velocity[a] != 0.0) | (m.omega[a] != 0.0);
    int id;
    st = dem_mesh_append(r->d, &m, "dem_snapshot_read", &id); /* takes m's arrays */
    memset(&m, 0, sizeof m);
    if (st != DEM_OK) st = lib_fail(r, st);
out:
    dem_mesh_free(&m);
    dem_free(xb);
    H5Gclose(mg);
    return st;
}

static dem_status read_walls(reader *r)
{
    hid_t g = H5Gopen2(r->f, "walls", H5P_DEFAULT);
    if (g < 0) return bad(r, "group 'walls' missing");
    dem_status st = DEM_OK;
    int64_t nw = r_rows(g, "plane_position_velocity");
    int32_t n_meshes = 0;
    int32_t *iv = dem_malloc((size_t)(nw > 0 ? nw : 1) * 3 * sizeof(int32_t));
    double *dv = dem_malloc((size_t)(nw > 0 ? nw : 1) * 4 * sizeof(double));
    if (nw < 0 || !iv || !dv || !r_dset(g, "plane_axis_side_material", H5T_NATIVE_INT32, (hsize_t)nw, 3, iv) ||
        !r_dset(g, "plane_position_velocity", H5T_NATIVE_DOUBLE, (hsize_t)nw, 4, dv) ||
        !r_attr(g, "mesh_count", H5T_NATIVE_INT32, 1, &n_meshes) || n_meshes < 0) {
        st = bad(r, "walls: plane wall tables or mesh count missing");
        goto out;
    }
    for (int64_t w = 0; w < nw; w++) {
        dem_plane_wall_def p = dem_default_plane_wall_def();
        p.axis = iv[3 * w];
        p.side = iv[3 * w + 1];
        p.material.index = iv[3 * w + 2];
        p.position = dv[4 * w];
        memcpy(p.velocity, dv + 4 * w + 1, 3 * sizeof(double));
        dem_plane_wall id;
        dem_status s = dem_plane_wall_add(r->d, &p, &id);
        if (s != DEM_OK) {
            st = lib_fail(r, s);
            goto out;
        }
    }
    for (int k = 0; k < n_meshes && st == DEM_OK; k++) st = read_mesh(r, g, k);
out:
    dem_free(iv);
    dem_free(dv);
    H5Gclose(g);
    return st;
}

static dem_status read_particles(reader *r, int64_t next_id)
{
    dem_domain *d = r->d;
    hid_t g = H5Gopen2(r->f, "particles", H5P_DEFAULT);
    if (g < 0) return bad(r, "group 'particles' missing");
    dem_status st = DEM_OK;
    int64_t n = r_rows(g, "id");
    if (n < 0 || n > INT32_MAX || !dem_particles_reserve(d, n, next_id)) {
        st = bad(r, n < 0 ? "particles/id missing" : "too many particles or out of memory");
        goto out;
    }
    const hsize_t hn = (hsize_t)n;
    if (!r_dset(g, "id", H5T_NATIVE_INT64, hn, 0, d->id) || !r_dset(g, "material", H5T_NATIVE_INT32, hn, 0, d->mat) ||
        !r_dset(g, "radius", H5T_NATIVE_DOUBLE, hn, 0, d->radius) || !r_dset(g, "position", H5T_NATIVE_DOUBLE, hn, 3, d->x) ||
        !r_dset(g, "velocity", H5T_NATIVE_DOUBLE, hn, 3, d->v) ||
        !r_dset(g, "angular_velocity", H5T_NATIVE_DOUBLE, hn, 3, d->w) ||
        !r_dset(g, "position_at_list_build", H5T_NATIVE_DOUBLE, hn, 3, d->x_build)) {
        st = bad(r, "particles: a dataset is missing or has the wrong shape");
        goto out;
    }
    for (int64_t k = 0; k < next_id; k++) d->index_of_id[k] = -1;
    d->r_max = 0.0;
    for (int64_t i = 0; i < n; i++) {
        if (d->id[i] < 0 || d->id[i] >= next_id || d->index_of_id[d->id[i]] >= 0) {
            st = bad(r, "particle ids are out of range or repeated");
            goto out;
        }
        if (d->mat[i] < 0 || d->mat[i] >= d->n_materials || !(d->radius[i] > 0.0) || !dem_is_finite(d->radius[i])) {
            st = bad(r, "a particle has an unknown material or a bad radius");
            goto out;
        }
        d->index_of_id[d->id[i]] = (int32_t)i;
        const double r = d->radius[i]; /* the same expression as dem_particles_add, to the bit */
        const double mass = d->materials[d->mat[i]].density * 4.0 / 3.0 * DEM_PI * r * r * r;
        d->inv_mass[i] = 1.0 / mass;
        d->inv_inertia[i] = 1.0 / (0.4 * mass * d->radius[i] * d->radius[i]);
        if (d->radius[i] > d->r_max) d->r_max = d->radius[i];
    }
    d->n = n;
    d->next_id = next_id;
out:
    H5Gclose(g);
    return st;
}

/* The Verlet list as it was: built from the stored build positions (particles and meshes). */
static dem_status rebuild_list(reader *r)
{
    dem_domain *d = r->d;
    const size_t bytes = (size_t)d->n * 3 * sizeof(double);
    double *now = dem_malloc(bytes + 8);
    double **mesh_now = dem_calloc((size_t)d->n_meshes + 1, sizeof *mesh_now);
    dem_status st = DEM_OK;
    if (!now || !mesh_now) {
        st = bad(r, "out of memory");
        goto out;
    }
    memcpy(now, d->x, bytes);
    memcpy(d->x, d->x_build, bytes);
    for (int k = 0; k < d->n_meshes; k++) { /* meshes at their build place */
        mesh_wall *m = &d->meshes[k];
        mesh_now[k] = m->x;
        m->x = dem_malloc((size_t)m->nv * 3 * sizeof(double));
        if (!m->x) {
            m->x = mesh_now[k];
            mesh_now[k] = NULL;
            st = bad(r, "out of memory");
            goto out;
        }
        memcpy(m->x, m->x_build, (size_t)m->nv * 3 * sizeof(double));
    }
    st = dem_neighbor_rebuild(d, NULL);
    if (st != DEM_OK) {
        st = lib_fail(r, st);
        goto out;
    }
    for (int64_t i = 0; i < d->n && st == DEM_OK; i++) /* the sort must have kept the stored order */
        if (d->perm[i] != (int32_t)i)
            st = bad(r, "the particle order is not the one of the last list build: the file was edited, or written by "
                        "a libdem that sorts particles differently (a bit-exact restart needs the same library)");
    memcpy(d->x, now, bytes);
out:
    for (int k = 0; k < d->n_meshes; k++)
        if (mesh_now && mesh_now[k]) {
            dem_free(d->meshes[k].x);
            d->meshes[k].x = mesh_now[k];
            dem_mesh_measure_disp(&d->meshes[k]); /* the build reset it at x_build */
        }
    dem_free(now);
    dem_free(mesh_now);
    return st;
}

static dem_status read_contacts(reader *r)
{
    dem_domain *d = r->d;
    hid_t g = H5Gopen2(r->f, "contacts", H5P_DEFAULT);
    if (g < 0) return bad(r, "group 'contacts' missing");
    dem_status st = DEM_OK;
    int64_t np = r_rows(g, "pair_ids"), nw = r_rows(g, "plane_ids"), nm = r_rows(g, "mesh_ids");
    contact_field pf[PAIR_FIELDS], wf[PLANE_FIELDS], mf[MESH_FIELDS];
    const int pw = pair_fields(d, pf), ww = plane_fields(d, wf), mw = mesh_fields(d, mf);
    const int width = contact_row_width(pw, ww, mw);
    int64_t cap = (np > nw ? np : nw) > nm ? (np > nw ? np : nw) : nm;
    int64_t *ids = dem_malloc((size_t)(cap + 1) * 2 * sizeof(int64_t));
    int32_t *iv = dem_malloc((size_t)(cap + 1) * 3 * sizeof(int32_t));
    double *h = dem_malloc((size_t)(cap + 1) * (size_t)width * sizeof(double));
    if (np < 0 || nw < 0 || nm < 0 || !ids || !iv || !h) {
        st = bad(r, "contact tables missing");
        goto out;
    }
#define ID_INDEX(id) (((id) >= 0 && (id) < d->next_id) ? d->index_of_id[(id)] : -1)
    pair_list *pl = &d->pairs_cur;
    if (!r_dset(g, "pair_ids", H5T_NATIVE_INT64, (hsize_t)np, 2, ids) || !r_dset(g, "pair_active", H5T_NATIVE_INT32, (hsize_t)np, 0, iv) ||
        !r_dset(g, "pair_history_reaction", H5T_NATIVE_DOUBLE, (hsize_t)np, (hsize_t)pw, h)) {
        st = bad(r, "contacts/pair_*: wrong shape");
        goto out;
    }
    /* entries not in the file were not touching: no history, empty reaction slot */
    if (pl->count > 0) {
        memset(pl->active, 0, (size_t)pl->count);
        memset(d->slot, 0, (size_t)pl->count * 6 * sizeof(double));
    }
    for (int64_t q = 0; q < np; q++) {
        int32_t i = ID_INDEX(ids[2 * q]), j = ID_INDEX(ids[2 * q + 1]);
        int64_t k = i < 0 ? -1 : pl->start[i];
        while (k >= 0 && k < pl->start[i + 1] && pl->j[k] != j) k++;
        if (i < 0 || j < 0 || k >= pl->start[i + 1]) {
            st = bad(r, "a pair history has no neighbour-list entry");
            goto out;
        }
        pl->active[k] = (uint8_t)(iv[q] != 0);
        unpack_fields(pf, PAIR_FIELDS, k, h + (int64_t)pw * q);
    }
    const wall_list *wl = &d->walls_cur;
    if (!r_dset(g, "plane_ids", H5T_NATIVE_INT64, (hsize_t)nw, 0, ids) || !r_dset(g, "plane_wall", H5T_NATIVE_INT32, (hsize_t)nw, 0, iv) ||
        !r_dset(g, "plane_history_force", H5T_NATIVE_DOUBLE, (hsize_t)nw, (hsize_t)ww, h)) {
        st = bad(r, "contacts/plane_*: wrong shape");
        goto out;
    }
    for (int64_t q = 0; q < nw; q++) {
        int32_t i = ID_INDEX(ids[q]);
        int64_t k = i < 0 ? -1 : wl->start[i];
        while (k >= 0 && k < wl->start[i + 1] && wl->wall[k] != iv[q]) k++;
        if (i < 0 || k >= wl->start[i + 1]) {
            st = bad(r, "a plane-wall history has no candidate entry");
            goto out;
        }
        unpack_fields(wf, PLANE_FIELDS, k, h + (int64_t)ww * q);
    }
    tri_list *tl = &d->tris_cur;
    if (!r_dset(g, "mesh_ids", H5T_NATIVE_INT64, (hsize_t)nm, 0, ids) ||
        !r_dset(g, "mesh_mesh_triangle_active", H5T_NATIVE_INT32, (hsize_t)nm, 3, iv) ||
        !r_dset(g, "mesh_history_force_point_normal", H5T_NATIVE_DOUBLE, (hsize_t)nm, (hsize_t)mw, h)) {
        st = bad(r, "contacts/mesh_*: wrong shape");
        goto out;
    }
    for (int64_t q = 0; q < nm; q++) {
        int32_t i = ID_INDEX(ids[q]);
        int64_t k = i < 0 ? -1 : tl->start[i];
        while (k >= 0 && k < tl->start[i + 1] && (tl->mesh[k] != iv[3 * q] || tl->tri[k] != iv[3 * q + 1])) k++;
        if (i < 0 || k >= tl->start[i + 1]) {
            st = bad(r, "a mesh contact history has no candidate entry");
            goto out;
        }
        tl->active[k] = (uint8_t)(iv[3 * q + 2] != 0);
        unpack_fields(mf, MESH_FIELDS, k, h + (int64_t)mw * q);
    }
#undef ID_INDEX
out:
    dem_free(ids);
    dem_free(iv);
    dem_free(h);
    H5Gclose(g);
    return st;
}

dem_status dem_snapshot_read(const char *path, dem_domain **out, char *msg, size_t msg_size)
{
    if (msg && msg_size) msg[0] = '\0';
    if (!out) return DEM_ERR_NULL;
    *out = NULL;
    if (!path) return DEM_ERR_NULL;
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    reader r = {-1, msg, msg_size, NULL, path};
    FILE *probe = fopen(path, "rb");
    if (!probe) {
        if (msg && msg_size) snprintf(msg, msg_size, "dem_snapshot_read: cannot open '%s'", path);
        return DEM_ERR_IO;
    }
    fclose(probe);
    if (H5Fis_hdf5(path) <= 0) return bad(&r, "not an HDF5 file (truncated or another format)");
    r.f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (r.f < 0) return bad(&r, "the HDF5 file cannot be opened (corrupt?)");
    dem_domain_def def;
    int64_t step, next_id;
    double time, mesh_disp;
    uint64_t seed;
    dem_status st = read_settings(&r, &def, &step, &time, &seed, &next_id, &mesh_disp);
    if (st == DEM_OK) {
        st = dem_domain_create(&def, &r.d, msg, msg_size);
        if (st != DEM_OK) st = DEM_ERR_FORMAT;
    }
    if (st == DEM_OK) st = read_materials(&r);
    if (st == DEM_OK) st = read_walls(&r);
    if (st == DEM_OK) st = read_particles(&r, next_id);
    double *f = NULL, *t = NULL;
    if (st == DEM_OK && r.d->n > 0) {
        dem_domain *d = r.d;
        hid_t g = H5Gopen2(r.f, "particles", H5P_DEFAULT);
        f = dem_malloc((size_t)d->n * 3 * sizeof(double));
        t = dem_malloc((size_t)d->n * 3 * sizeof(double));
        if (g < 0 || !f || !t || !r_dset(g, "force", H5T_NATIVE_DOUBLE, (hsize_t)d->n, 3, f) ||
            !r_dset(g, "torque", H5T_NATIVE_DOUBLE, (hsize_t)d->n, 3, t))
            st = bad(&r, "particles/force or torque missing");
        if (g >= 0) H5Gclose(g);
        if (st == DEM_OK) st = rebuild_list(&r);
        if (st == DEM_OK) st = read_contacts(&r);
        if (st == DEM_OK) { /* the rebuild used the force array as scratch: now the real ones */
            memcpy(d->f, f, (size_t)d->n * 3 * sizeof(double));
            memcpy(d->t, t, (size_t)d->n * 3 * sizeof(double));
            d->forces_valid = 1;
        }
    }
    dem_free(f);
    dem_free(t);
    if (st == DEM_OK) {
        r.d->step = step;
        r.d->time = time;
        r.d->seed = seed;
        r.d->next_id = next_id;
        r.d->mesh_disp = mesh_disp;
    }
    H5Fclose(r.f);
    if (st != DEM_OK) {
        dem_domain_destroy(r.d);
        return st;
    }
    *out = r.d;
    return DEM_OK;
}
#endif /* DEM_NO_HDF5 */
