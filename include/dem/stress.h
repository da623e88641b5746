/* libdem — average stress in a region (Love–Weber) and its parts. */
#ifndef DEM_STRESS_H
#define DEM_STRESS_H

#include "types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum dem_region_kind {
    DEM_REGION_BOX = 0,            /* lo <= x <= hi */
    DEM_REGION_CYLINDER = 1,       /* radius <= r_outer about the axis, h_lo <= height <= h_hi */
    DEM_REGION_ANNULAR_SECTOR = 2  /* r_inner <= radius <= r_outer, angle_lo <= angle <= angle_hi */
} dem_region_kind;

/* A region. Cylinder and sector: the axis is coordinate axis `axis` through `centre`;
 * height is measured along it from centre; the angle is atan2(x[(axis+2)%3], x[(axis+1)%3])
 * about the centre (for axis 2: atan2(y, x)), in radians, angle_hi - angle_lo in (0, 2 pi]. */
typedef struct dem_region {
    dem_region_kind kind;
    double lo[3], hi[3];       /* box corners, m */
    double centre[3];          /* m */
    int axis;                  /* 0, 1, 2 */
    double r_inner, r_outer;   /* m */
    double h_lo, h_hi;         /* m */
    double angle_lo, angle_hi; /* rad */
} dem_region;

/* Stress tensors are row-major 3x3, Pa, compression positive (soil-mechanics sign):
 *   sigma = (1/V) sum over particles p with centre in V of
 *           [ -sum over contacts c of p:  f_c (x) (x_c - x_p)   +   m_p u_p (x) u_p ]
 * with f_c the contact force on p, x_c the contact point, u_p = v_p - (mass-weighted mean
 * velocity in V). Contacts with walls count like any other, acting at the wall surface. */
typedef struct dem_stress {
    double total[9];
    double contact[9];
    double kinetic[9];
    double volume;             /* m^3 */
    int64_t particle_count;    /* centres inside */
    double solid_fraction;     /* volume of the spheres whose centres are inside / V */
    double mean_velocity[3];   /* m/s, mass-weighted */
} dem_stress;

DEM_API dem_region dem_default_region(void); /* a unit box at the origin */
DEM_API dem_status dem_region_stress(dem_domain *domain, const dem_region *region, dem_stress *out);

/* Every contact with overlap > 0 of the current state (forces brought up to date first when
 * needed, as dem_domain_step(d, 0)): particle pairs, plane walls and mesh triangles. *count
 * gets their number; up to `capacity` of them are written to out (out may be NULL with
 * capacity 0 to ask for the number). DEM_ERR_INVALID_ARGUMENT when capacity < *count (the
 * first `capacity` are written). */
DEM_API dem_status dem_contacts_get(dem_domain *domain, dem_contact *out, int64_t capacity, int64_t *count);

#ifdef __cplusplus
}
#endif
#endif
