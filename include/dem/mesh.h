/* libdem — triangle-mesh walls: STL or caller arrays, welded, moving, load-controlled.
 *
 * Mesh walls have their own index space (0, 1, ... in order of creation), separate from the
 * analytic plane walls. A sphere touching a mesh feels one contact per genuine touching point
 * of the surface: a shared edge or vertex counts once, and the edges and vertices of a flat
 * region feel exactly like the plane (see docs/walls.md for the rule). */
#ifndef DEM_MESH_H
#define DEM_MESH_H

#include "types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dem_mesh_def {
    double scale;          /* coordinates are multiplied by this on load (1e-3 for mm files), > 0 */
    double offset[3];      /* m, added after scaling */
    double weld_tolerance; /* m, vertices closer than this are merged; <= 0: 1e-6 x bounding-box diagonal */
    dem_material material; /* wall material */
} dem_mesh_def;

/* What the loader found. */
typedef struct dem_mesh_info {
    int64_t vertex_count;       /* after welding */
    int64_t triangle_count;     /* kept */
    int64_t edge_count;
    int64_t boundary_edge_count;    /* edges with one triangle (an open mesh) */
    int64_t nonmanifold_edge_count; /* edges with more than two triangles */
    int64_t skipped_degenerate;     /* zero-area triangles dropped */
    int64_t input_triangle_count;   /* as read */
    double lo[3], hi[3];            /* current bounding box, m */
} dem_mesh_info;

/* Load control along a direction: the wall moves along `direction` (unit vector, the
 * direction that compresses the bulk) at speed
 *     v = max_speed * clamp((F_target - F) / (proportional_band * F_target), -1, 1)
 * where F is the force the particles exert on the wall along -direction (N), low-pass
 * filtered with time constant filter_time. F_target = target_force, or target_stress * area
 * when area > 0. Full speed far from the target, proportional inside the band: a first-order
 * approach with time constant proportional_band * F_target / (max_speed * k_bulk). */
typedef struct dem_servo_def {
    double direction[3];      /* unit vector, m/m */
    double target_force;      /* N, > 0 (used when area == 0) */
    double target_stress;     /* Pa (used when area > 0) */
    double area;              /* m^2, 0: force target */
    double max_speed;         /* m/s, > 0, default 0.05 */
    double proportional_band; /* fraction of the target, > 0, default 0.2 */
    double filter_time;       /* s, >= 0, default 0 (no filter) */
} dem_servo_def;

DEM_API dem_mesh_def dem_default_mesh_def(void);
DEM_API dem_servo_def dem_default_servo_def(void);

/* Loads an STL file (ASCII or binary, detected from the content). Zero-area triangles are
 * skipped and counted (dem_mesh_wall_info). Fails with DEM_ERR_IO (cannot read) or
 * DEM_ERR_FORMAT (malformed, NaN/inf, size mismatch), naming the problem; the domain is
 * unchanged then. Particles the mesh would cut are refused with DEM_ERR_OVERLAP. */
DEM_API dem_status dem_mesh_wall_add_stl(dem_domain *domain, const char *path, const dem_mesh_def *def, dem_mesh_wall *mesh);
/* Same from caller arrays: vertices 3 x n_vertices (m, before scale/offset), triangles
 * 3 x n_triangles vertex indices. */
DEM_API dem_status dem_mesh_wall_add(dem_domain *domain, int64_t n_vertices, const double *vertices,
                                     int64_t n_triangles, const int32_t *triangles, const dem_mesh_def *def,
                                     dem_mesh_wall *mesh);
DEM_API int dem_mesh_wall_count(const dem_domain *domain);
DEM_API dem_status dem_mesh_wall_info(const dem_domain *domain, dem_mesh_wall mesh, dem_mesh_info *info);
/* Current (moved) vertices, 3 x vertex_count, and triangles, 3 x triangle_count, into buffers
 * with room for `capacity` vertices / triangles (DEM_ERR_INVALID_ARGUMENT when too small). */
DEM_API dem_status dem_mesh_wall_get_vertices(const dem_domain *domain, dem_mesh_wall mesh, double *vertices, int64_t capacity);
DEM_API dem_status dem_mesh_wall_get_triangles(const dem_domain *domain, dem_mesh_wall mesh, int32_t *triangles,
                                               int64_t capacity);

/* Prescribed rigid motion from now on: translation velocity (m/s) plus rotation at
 * angular_velocity (rad/s, vector along the axis) about an axis through `centre` (m, a point
 * that moves with the wall). NULL angular_velocity/centre: no rotation. Changeable between
 * steps; contacts feel the surface velocity v + w x (p - c). Switches a servo off. */
DEM_API dem_status dem_mesh_wall_set_motion(dem_domain *domain, dem_mesh_wall mesh, const double velocity[3],
                                            const double angular_velocity[3], const double centre[3]);
/* Load control (replaces the translation velocity; a rotation set before is kept). */
DEM_API dem_status dem_mesh_wall_set_servo(dem_domain *domain, dem_mesh_wall mesh, const dem_servo_def *def);
DEM_API dem_status dem_mesh_wall_servo_off(dem_domain *domain, dem_mesh_wall mesh);
/* Rigid pose relative to the loaded mesh: x = R x0 + t (R row-major 3x3). */
DEM_API dem_status dem_mesh_wall_get_pose(const dem_domain *domain, dem_mesh_wall mesh, double translation[3],
                                          double rotation[9]);
DEM_API dem_status dem_mesh_wall_get_velocity(const dem_domain *domain, dem_mesh_wall mesh, double velocity[3],
                                              double angular_velocity[3]);

/* Total force the particles exerted on the wall during the last step (N), and its torque
 * about `point` (N m); point NULL: the origin. */
DEM_API dem_status dem_mesh_wall_force(const dem_domain *domain, dem_mesh_wall mesh, const double point[3], double force[3],
                                       double torque[3]);
/* Time average of the wall force over every step since the last reset: a lid's stress without
 * the step-to-step rattle of a snapshot. Reset starts (or restarts) the average; the mean is
 * sum(F dt) / sum(dt) and its torque about `point` (NULL: the origin); `seconds` receives the
 * averaged time (0, and zero force, when no step was taken since the reset). */
DEM_API dem_status dem_mesh_wall_reset_mean_force(dem_domain *domain, dem_mesh_wall mesh);
DEM_API dem_status dem_mesh_wall_mean_force(const dem_domain *domain, dem_mesh_wall mesh, const double point[3],
                                            double force[3], double torque[3], double *seconds);
/* Force on each triangle, 3 x triangle_count (N), into a buffer with room for `capacity` triangles. */
DEM_API dem_status dem_mesh_wall_triangle_forces(const dem_domain *domain, dem_mesh_wall mesh, double *forces, int64_t capacity);
/* Normal and shear stress of the wall force over `area` (m^2) for the unit `normal`:
 * sigma_n = F.n / A, tau = |F - (F.n) n| / A (Pa). */
DEM_API dem_status dem_mesh_wall_stress(const dem_domain *domain, dem_mesh_wall mesh, const double normal[3], double area,
                                        double *normal_stress, double *shear_stress);

#ifdef __cplusplus
}
#endif
#endif
