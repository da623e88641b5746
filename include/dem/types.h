/* libdem — definition structs. Get one from dem_default_*_def(), tweak, pass to create/set. */
#ifndef DEM_TYPES_H
#define DEM_TYPES_H

#include "base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dem_domain dem_domain; /* opaque */
typedef int64_t dem_particle_id;       /* stable across sorting, removal and restarts */

/* Typed handles: a material, a plane wall or a mesh wall is named by a struct holding its index
 * (0, 1, ... in creation order), so passing one kind where another is expected does not compile.
 * Arrays of materials (one per particle) are arrays of dem_material: int32 indices in memory. */
typedef struct dem_material { int32_t index; } dem_material;
typedef struct dem_plane_wall { int32_t index; } dem_plane_wall;
typedef struct dem_mesh_wall { int32_t index; } dem_mesh_wall;

/* The simulation box. Closed axes: a particle leaving [lo, hi] is an error
 * (DEM_ERR_OUT_OF_BOUNDS); periodic axes wrap. */
typedef struct dem_domain_def {
    double lo[3], hi[3];        /* m */
    int periodic[3];            /* 0/1 per axis */
    double gravity[3];          /* m/s^2, default (0, 0, -9.81) */
    double dt;                  /* s, default 1e-5 */
    double skin;                /* m, neighbour-list skin, default 2e-4 */
    int num_threads;            /* OpenMP threads, default 1; results do not depend on it */
    double max_overlap_ratio;   /* overlap / smaller radius that counts as runaway, default 0.3 */
    double insert_overlap_ratio;/* overlap / smaller radius refused at insertion, default 1e-3 */
    double reference_velocity;  /* m/s, impact speed for the Hertz contact-time estimate, default 1 */
} dem_domain_def;

/* Per-material constants. */
typedef struct dem_material_def {
    double youngs_modulus; /* E, Pa (> 0) */
    double poisson_ratio;  /* nu, in (-1, 0.5) */
    double density;        /* kg/m^3 (> 0); ignored for wall materials */
    double shear_modulus;  /* G, Pa (> 0), for a material whose G is not E / (2 (1 + nu));
                            * 0 (the default): isotropic, G = E / (2 (1 + nu)) */
} dem_material_def;

/* Rolling resistance model; every model caps |M_r| <= mu_r R* |F_n|. */
typedef enum dem_rolling_model {
    DEM_ROLLING_CDT = 0,   /* constant directional torque -mu_r R* F_n w_rel/|w_rel| */
    DEM_ROLLING_EPSD = 1,  /* elastic-plastic spring-dashpot, k_r = 2.25 k_n mu_r^2 R*^2 (Ai et al. 2011) */
    DEM_ROLLING_EPSD2 = 2  /* spring k_r = k_t R*^2, no dashpot (seed 000 eq. 4); default */
} dem_rolling_model;

/* Constants of a material pair (particle–particle or particle–wall). */
typedef struct dem_pair_def {
    double restitution;       /* e in (0, 1]; delivered e equals this (damping is corrected) */
    double friction;          /* mu_s >= 0, sliding (Coulomb) */
    double rolling_friction;  /* mu_r >= 0 */
    dem_rolling_model rolling_model;
    double rolling_damping;   /* EPSD only: dashpot as a fraction of critical, >= 0, default 0 */
} dem_pair_def;

/* Axis-aligned analytic plane wall: the half-space the particles live in is
 * x[axis] >= position when side = +1, x[axis] <= position when side = -1. */
typedef struct dem_plane_wall_def {
    int axis;          /* 0, 1, 2 */
    int side;          /* +1 or -1: direction of the wall normal, pointing into the domain */
    double position;   /* m */
    dem_material material; /* wall material */
    double velocity[3];/* m/s, surface velocity felt by the contacts (the plane does not move) */
} dem_plane_wall_def;

/* Diagnostics of the current state. */
typedef struct dem_diagnostics {
    int64_t step;
    double time;                 /* s */
    int64_t particle_count;
    int64_t contact_count;       /* particle–particle + particle–wall contacts with overlap > 0 */
    int64_t wall_contact_count;  /* of which particle–wall */
    double kinetic_energy;       /* J, translational + rotational */
    double elastic_energy;       /* J, normal Hertz potential (8/15) E* sqrt(R*) d^(5/2) in the contacts */
    double max_overlap_ratio;    /* max overlap / smaller radius */
    double momentum[3];          /* kg m/s */
} dem_diagnostics;

/* One contact of the current state (dem_contacts_get), seen from particle i. */
typedef enum dem_contact_kind {
    DEM_CONTACT_PARTICLE = 0, /* partner: particle id j */
    DEM_CONTACT_PLANE = 1,    /* partner: plane wall `wall` */
    DEM_CONTACT_MESH = 2      /* partner: mesh wall `wall`, its triangle `triangle` */
} dem_contact_kind;

typedef struct dem_contact {
    dem_particle_id i;     /* the particle */
    dem_particle_id j;     /* the partner particle (-1 for a wall) */
    int32_t kind;          /* dem_contact_kind */
    int32_t wall;          /* plane or mesh wall index (-1 for a particle) */
    int64_t triangle;      /* mesh triangle (-1 otherwise) */
    double point[3];       /* m, the contact point: the middle of the overlap (pairs), on the surface (walls) */
    double normal[3];      /* unit normal, from the partner towards i */
    double force[3];       /* N, the contact force on i (the partner gets the opposite) */
    double overlap;        /* m */
    double normal_force;   /* N, force . normal (> 0 pushes i away from the partner) */
    double tangential_force; /* N, the magnitude of the force's tangential part */
    int32_t sliding;       /* 1: the tangential force is at the Coulomb limit mu_s F_n (the contact slips) */
    int32_t reserved;
} dem_contact;

/* Accumulated wall-clock time per phase since creation or the last reset. */
typedef struct dem_profile {
    double neighbor_s;     /* cell binning, sorting, Verlet list build, history transfer */
    double contact_s;      /* the force sweep: pair and wall contacts, force gathering, and the
                            * Verlet kicks and drift fused with them (see docs/libdem.md) */
    double integrate_s;    /* the separate opening kick + drift of the first step of a call */
    int64_t steps;
    int64_t neighbor_builds;
    int64_t neighbor_pairs;  /* entries of the current (half) Verlet list */
    int64_t steps_fewer_threads; /* steps run on fewer threads than num_threads (dem_domain_set_adaptive_threads) */
} dem_profile;

/* Time-step estimates for the current particles and materials. */
typedef struct dem_timestep_info {
    double rayleigh_time;       /* s, min over particles of pi R sqrt(rho/G)/(0.1631 nu + 0.8766) */
    double hertz_contact_time;  /* s, head-on contact duration at reference_velocity, min over material pairs */
    double suggested_dt;        /* s, min(0.1 rayleigh_time, hertz_contact_time / 50) */
} dem_timestep_info;

#ifdef __cplusplus
}
#endif
#endif
