/* Shared by the snapshot writer and reader (internal). */
#ifndef DEM_SNAPSHOT_H5_H
#define DEM_SNAPSHOT_H5_H

#include "internal.h"
#include <hdf5.h>
#include <stdio.h>
#include <string.h>

#define FORMAT_NAME "libdem snapshot"
#define FORMAT_VERSION 1

/* The per-entry double fields of each contact layout, in the file's column order: one table
 * that the writer packs rows from and the reader unpacks rows into, so the two cannot drift. */
typedef struct contact_field {
    double *base;  /* the list's array (width doubles per entry) */
    int width;
} contact_field;

enum { PAIR_FIELDS = 2, PLANE_FIELDS = 2, MESH_FIELDS = 4 };

/* pair_history_reaction: tangential spring and rolling torque (6), the reaction slot (6) */
static inline int pair_fields(const dem_domain *d, contact_field f[PAIR_FIELDS])
{
    f[0] = (contact_field){d->pairs_cur.hist, 6};
    f[1] = (contact_field){d->slot, 6};
    return 6 + 6;
}

/* plane_history_force: spring and rolling torque (6), force on the particle (3) */
static inline int plane_fields(const dem_domain *d, contact_field f[PLANE_FIELDS])
{
    f[0] = (contact_field){d->walls_cur.hist, 6};
    f[1] = (contact_field){d->walls_cur.force, 3};
    return 6 + 3;
}

/* mesh_history_force_point_normal: spring and rolling torque (6), force, point, normal (3 each) */
static inline int mesh_fields(const dem_domain *d, contact_field f[MESH_FIELDS])
{
    f[0] = (contact_field){d->tris_cur.hist, 6};
    f[1] = (contact_field){d->tris_cur.force, 3};
    f[2] = (contact_field){d->tris_cur.point, 3};
    f[3] = (contact_field){d->tris_cur.normal, 3};
    return 6 + 3 + 3 + 3;
}

/* The widest row of the three layouts: one buffer serves them all. */
static inline int contact_row_width(int pair_width, int plane_width, int mesh_width)
{
    const int w = pair_width > plane_width ? pair_width : plane_width;
    return w > mesh_width ? w : mesh_width;
}

/* Entry k of the lists -> one file row, and back. */
static inline void pack_fields(const contact_field *f, int n, int64_t k, double *row)
{
    for (int a = 0; a < n; row += f[a].width, a++) memcpy(row, f[a].base + (int64_t)f[a].width * k, (size_t)f[a].width * sizeof(double));
}

static inline void unpack_fields(const contact_field *f, int n, int64_t k, const double *row)
{
    for (int a = 0; a < n; row += f[a].width, a++) memcpy(f[a].base + (int64_t)f[a].width * k, row, (size_t)f[a].width * sizeof(double));
}

#endif
