/* libdem — a C99 + OpenMP discrete element method library. Umbrella header.
 *
 * Life cycle: dem_domain_create -> dem_material_create -> dem_pair_set ->
 * dem_particles_add / dem_plane_wall_add -> dem_domain_step ... -> dem_domain_destroy.
 * Every fallible call returns a dem_status; dem_domain_last_error() explains the last
 * failure in words. A failed call leaves the domain as it was (except numerical failures
 * during stepping, which stop the run and name the particle). Units are SI. */
#ifndef DEM_DEM_H
#define DEM_DEM_H

#include "base.h"
#include "types.h"
#include "mesh.h"
#include "stress.h"
#include "io.h"
#include "mlp.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- domain ---------------------------------------------------------------------- */
DEM_API dem_domain_def dem_default_domain_def(void);
/* Creates a domain. On failure *out is NULL and, when msg is not NULL, the reason is
 * written into msg (at most msg_size bytes, NUL-terminated). */
DEM_API dem_status dem_domain_create(const dem_domain_def *def, dem_domain **out,
                                     char *msg, size_t msg_size);
DEM_API void dem_domain_destroy(dem_domain *domain);
/* Words for the last failed (or warning) call on this domain; "" after success. */
DEM_API const char *dem_domain_last_error(const dem_domain *domain);
DEM_API dem_status dem_domain_get_def(const dem_domain *domain, dem_domain_def *def);
DEM_API dem_status dem_domain_set_dt(dem_domain *domain, double dt);
DEM_API dem_status dem_domain_set_gravity(dem_domain *domain, const double gravity[3]);
DEM_API dem_status dem_domain_set_num_threads(dem_domain *domain, int num_threads);
/* 1 (the default): the steps use fewer than num_threads threads while that measures faster —
 * a machine whose other processes take cores, or a system too small for the team; the choice
 * is re-measured every 0.25-8 s of stepping. 0: always num_threads. Results do not depend on it. */
DEM_API dem_status dem_domain_set_adaptive_threads(dem_domain *domain, int adaptive);

/* Advances n_steps steps of velocity Verlet. Returns DEM_WARN_TIMESTEP_LARGE when
 * dt > 0.2 Rayleigh time (steps anyway), DEM_ERR_UNSTABLE_TIMESTEP when dt exceeds the
 * Rayleigh time (does nothing), DEM_ERR_NUMERICAL / DEM_ERR_OUT_OF_BOUNDS /
 * DEM_ERR_RUNAWAY_OVERLAP when the run breaks (stops at that step, names the particle). */
DEM_API dem_status dem_domain_step(dem_domain *domain, int64_t n_steps);
DEM_API dem_status dem_domain_timestep_info(dem_domain *domain, dem_timestep_info *info);
DEM_API dem_status dem_domain_diagnostics(dem_domain *domain, dem_diagnostics *diag);
DEM_API dem_status dem_domain_profile(const dem_domain *domain, dem_profile *profile);
DEM_API dem_status dem_domain_profile_reset(dem_domain *domain);
/* 64-bit FNV-1a hash of ids, positions, velocities, angular velocities (bitwise). */
DEM_API dem_status dem_domain_state_hash(const dem_domain *domain, uint64_t *hash);
/* Bytes held by the domain's arrays (particles, lists, histories, mesh walls and their bins). */
DEM_API size_t dem_domain_memory_bytes(const dem_domain *domain);

/* ---- materials and material pairs ---------------------------------------------- */
DEM_API dem_material_def dem_default_material_def(void);   /* glass-like: E 5 MPa, nu 0.25, rho 2500 */
DEM_API dem_status dem_material_create(dem_domain *domain, const dem_material_def *def, dem_material *material);
DEM_API int dem_material_count(const dem_domain *domain);
DEM_API dem_pair_def dem_default_pair_def(void);            /* e 0.5, mu_s 0.5, mu_r 0, EPSD2 */
/* Sets the constants of pair (a, b) (symmetric). Pairs never set use dem_default_pair_def(). */
DEM_API dem_status dem_pair_set(dem_domain *domain, dem_material a, dem_material b, const dem_pair_def *def);
DEM_API dem_status dem_pair_get(const dem_domain *domain, dem_material a, dem_material b, dem_pair_def *def);
/* The damping constant actually used so that the delivered restitution equals the requested
 * one with the normal force clipped at zero (gamma = factor * sqrt(S m*)). */
DEM_API dem_status dem_pair_damping_factor(const dem_domain *domain, dem_material a, dem_material b,
                                           double *factor);

/* ---- effects (optional physics, see docs/effects.md) ----------------------------- */
DEM_API int dem_effect_count(void);
/* Name, one-line summary and parameter count of effect number i (0 <= i < count). */
DEM_API dem_status dem_effect_info(int index, const char **name, const char **summary, int *n_params);
/* Name, unit and neutral (switch-off) value of parameter p of effect i. */
DEM_API dem_status dem_effect_param_info(int index, int param, const char **name, const char **unit,
                                         double *neutral);
/* The values parameter p of effect i accepts: [min, max], closed (dem_pair_set_effect refuses
 * any other), so a front-end can check a campaign's range before it runs anything. */
DEM_API dem_status dem_effect_param_range(int index, int param, double *min, double *max);
/* Switches an effect on for a material pair with the given parameters (all of them).
 * Setting every parameter to its neutral value switches it off. */
DEM_API dem_status dem_pair_set_effect(dem_domain *domain, dem_material a, dem_material b,
                                       const char *effect, const double *params, int n_params);

/* ---- particles ------------------------------------------------------------------- */
/* Adds n spheres. position: 3n, radius: n, material: n; velocity and angular_velocity:
 * 3n or NULL (zero). ids: n or NULL, receives the new stable ids. All-or-nothing: on any
 * bad value (NaN, radius <= 0, unknown material, outside bounds, overlap with a particle
 * or wall beyond insert_overlap_ratio) nothing is added and the message names the index. */
DEM_API dem_status dem_particles_add(dem_domain *domain, int64_t n, const double *position,
                                     const double *radius, const dem_material *material, const double *velocity,
                                     const double *angular_velocity, dem_particle_id *ids);
DEM_API dem_status dem_particles_remove(dem_domain *domain, int64_t n, const dem_particle_id *ids);
DEM_API int64_t dem_particle_count(const dem_domain *domain);
/* Read-back, in ascending id order, into caller buffers with room for `capacity` particles
 * (x3 doubles for vectors): DEM_ERR_INVALID_ARGUMENT, nothing written, when capacity <
 * dem_particle_count(). Forces and torques are the contact (+ wall) parts of the last step. */
DEM_API dem_status dem_particles_get_ids(const dem_domain *domain, dem_particle_id *ids, int64_t capacity);
DEM_API dem_status dem_particles_get_positions(const dem_domain *domain, double *position, int64_t capacity);
DEM_API dem_status dem_particles_get_velocities(const dem_domain *domain, double *velocity, int64_t capacity);
DEM_API dem_status dem_particles_get_angular_velocities(const dem_domain *domain, double *angular_velocity,
                                                        int64_t capacity);
DEM_API dem_status dem_particles_get_forces(const dem_domain *domain, double *force, int64_t capacity);
DEM_API dem_status dem_particles_get_torques(const dem_domain *domain, double *torque, int64_t capacity);
DEM_API dem_status dem_particles_get_radii(const dem_domain *domain, double *radius, int64_t capacity);
/* Overwrite velocities / angular velocities (ascending id order, count entries x 3). */
DEM_API dem_status dem_particles_set_velocities(dem_domain *domain, const double *velocity);
DEM_API dem_status dem_particles_set_angular_velocities(dem_domain *domain, const double *angular_velocity);

/* ---- analytic plane walls -------------------------------------------------------- */
DEM_API dem_plane_wall_def dem_default_plane_wall_def(void); /* floor z >= 0, material 0 */
DEM_API dem_status dem_plane_wall_add(dem_domain *domain, const dem_plane_wall_def *def, dem_plane_wall *wall);
DEM_API dem_status dem_plane_wall_set_velocity(dem_domain *domain, dem_plane_wall wall, const double velocity[3]);
/* Total force exerted by the particles on the wall during the last step (N). */
DEM_API dem_status dem_plane_wall_force(const dem_domain *domain, dem_plane_wall wall, double force[3]);
/* Time-averaged force (N) over the steps since the last reset (as for mesh walls, mesh.h):
 * reset starts or restarts the average; *seconds (may be NULL) gets the time averaged over, and
 * the force is zero before the first step. Not part of snapshots. */
DEM_API dem_status dem_plane_wall_reset_mean_force(dem_domain *domain, dem_plane_wall wall);
DEM_API dem_status dem_plane_wall_mean_force(const dem_domain *domain, dem_plane_wall wall, double force[3], double *seconds);

#ifdef __cplusplus
}
#endif
#endif
