/* The three contact lists — pair (Verlet) entries, plane-wall candidates, triangle candidates —
 * each a CSR over the particles, each entry's history in one layout: 6 doubles, the tangential
 * spring (3) then the rolling torque (3), which contact_law() takes as (h, h + 3). The pair
 * entries' reaction slots live beside the particles (dem_domain.slot). Built by neighbor.c
 * (pairs, planes) and mesh_bins.c (triangles), histories carried over between builds. */
#ifndef DEM_CONTACT_LISTS_H
#define DEM_CONTACT_LISTS_H

#include <stdint.h>

/* Mesh-triangle contact candidates, grouped by particle (CSR over particles). An entry is
 * "active" when it carried an accepted contact at the last evaluation. */
typedef struct tri_list {
    int64_t n_rows;          /* particles covered */
    int64_t count, capacity;
    int64_t *start;          /* n + 1 */
    int64_t start_cap;       /* entries allocated for start (grown, never shrunk: no allocation in a warm step) */
    int32_t *mesh, *tri;
    uint8_t *active;
    double *hist;            /* 6 per entry: tangential spring (3), rolling torque (3) */
    double *force;           /* 3 per entry: force on the particle, last step */
    double *torque;          /* 3 per entry: torque on the particle, kept only from the contact's
                              * evaluation to the particle's finish within one sweep */
    double *point;           /* 3 per entry: contact point, last step */
    double *normal;          /* 3 per entry: contact normal (towards the particle), last step */
    double *gap;             /* per entry: distance from the particle to the triangle at the build,
                              * less its radius: no contact before particle and triangle have moved
                              * that far together (mesh_contact.c skips the entry until then) */
} tri_list;

/* Verlet neighbour list, half (each pair once), CSR by row particle i. Per entry: the
 * partner j, the periodic image code of j, the contact histories, and whether the pair
 * touched at the last evaluation (its reaction slot then holds its force, where the slot
 * is current: see `slot`). */
typedef struct pair_list {
    int64_t n_rows;       /* particles covered */
    int64_t count, capacity;
    int64_t *start;       /* n_rows + 1 */
    int64_t start_cap;    /* entries allocated for start */
    int32_t *j;
    uint8_t *image;       /* 0..26: periodic shift of j, 13 = none */
    uint8_t *active;
    double *hist;         /* 6 per entry: tangential spring xi (3), rolling torque (3) */
} pair_list;

/* Wall contact candidates, grouped by particle (CSR over particles). */
typedef struct wall_list {
    int64_t count, capacity;
    int64_t *start;       /* n + 1 */
    int64_t start_cap;    /* entries allocated for start */
    int32_t *wall;
    double *hist;         /* 6 per entry: tangential spring (3), rolling torque (3) */
    double *force;        /* 3 per entry: force on the particle, last step */
} wall_list;

/* One touching contact of particle i as dem_visit_contacts (contact_visit.c) hands it over. */
typedef struct contact_view {
    int64_t i;            /* the particle (internal index) */
    int kind;             /* DEM_CONTACT_PARTICLE, _PLANE or _MESH */
    int64_t k;            /* its entry in that list */
    int32_t j;            /* the partner particle (pairs), else -1 */
    int partner_material; /* the partner particle's, plane wall's or mesh's material */
    double n[3];          /* pairs: x_i - x_j (j's periodic image), not normalised; walls: unit normal towards i */
    double dist;          /* pairs: |n|; plane: centre-to-plane distance; mesh: centre-to-contact-point distance */
    double overlap;       /* pairs and planes > 0; mesh: as evaluated (VISIT_EVALUATED may hand over <= 0) */
    const double *point;  /* mesh: the contact point (3); else NULL */
    const double *force;  /* on i, from the last evaluation (pairs: the reaction slot) */
} contact_view;

/* VISIT_EVALUATED: the contacts the last force evaluation had (pairs flagged active, mesh
 * contacts selected); VISIT_GEOMETRIC: every pair and plane entry that overlaps now (also
 * before any evaluation), mesh contacts as selected and still overlapping. */
enum { VISIT_EVALUATED = 0, VISIT_GEOMETRIC = 1 };
struct dem_domain;
typedef void (*contact_visitor)(const struct dem_domain *d, const contact_view *c, void *ctx);
void dem_visit_contacts(const struct dem_domain *d, int64_t i, int mode, contact_visitor fn, void *ctx);

#endif
