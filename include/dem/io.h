/* libdem — output: HDF5 snapshots (restartable) and PNG renderings. */
#ifndef DEM_IO_H
#define DEM_IO_H

#include "types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The caller's run seed (libdem draws no random numbers; the seed of whatever placed the
 * particles is recorded in snapshots so a run can be reproduced). */
DEM_API dem_status dem_domain_set_seed(dem_domain *domain, uint64_t seed);
DEM_API uint64_t dem_domain_seed(const dem_domain *domain);

/* Writes the complete state to an HDF5 file (layout: docs/snapshot.md): particles,
 * materials, material pairs and effects, walls with their motion and servo state, contact
 * histories, and as attributes the domain settings, step, time, seed, library version.
 * Brings the forces up to date first when needed (as dem_domain_step(d, 0)). */
DEM_API dem_status dem_snapshot_write(dem_domain *domain, const char *path);
/* Creates a new domain from a snapshot. Stepping it gives results bit-for-bit identical to
 * the run that wrote it, continued without interruption. Fails with DEM_ERR_IO (cannot open)
 * or DEM_ERR_FORMAT (not a libdem snapshot, missing or inconsistent data), saying what. */
DEM_API dem_status dem_snapshot_read(const char *path, dem_domain **out, char *msg, size_t msg_size);

/* VTK XML unstructured grids (.vtu, ASCII, exact) for ParaView and other tools. Particles:
 * one vertex per sphere with point data radius, velocity, angular_velocity, force (contact
 * force), id and material; the field TIME is the domain time. A mesh wall: its triangles at
 * the current pose with cell data force (the force the particles exert on each triangle).
 * Forces are brought up to date first when needed (as dem_domain_step(d, 0)). DEM_ERR_IO when
 * the file cannot be written; DEM_ERR_UNKNOWN_WALL for a mesh index out of range. */
DEM_API dem_status dem_vtk_write_particles(dem_domain *domain, const char *path);
DEM_API dem_status dem_vtk_write_mesh(dem_domain *domain, dem_mesh_wall mesh, const char *path);

typedef enum dem_color_mode {
    DEM_COLOR_MATERIAL = 0, /* a fixed palette by material */
    DEM_COLOR_SCALAR = 1,   /* a per-particle scalar mapped through a blue-to-red colour map */
    DEM_COLOR_GREY = 2      /* grey levels by material (seed 001's frames) */
} dem_color_mode;

/* Orthographic view along coordinate axis view_axis, seen from its negative side (camera
 * at -infinity looking towards +axis): axis 1 (front view) shows x to the right and z up;
 * axis 0 shows y right, z up; axis 2 shows x right, y up. The window [lo, hi] is in the
 * two image coordinates (m). Spheres are shaded discs with exact depth ordering (z-buffer). */
typedef struct dem_render_def {
    int width, height;          /* pixels, 1..16384 */
    int view_axis;              /* 0, 1, 2 */
    double lo[2], hi[2];        /* m, image window: (right, up) coordinates */
    dem_color_mode color_mode;
    const double *scalar;       /* DEM_COLOR_SCALAR: one value per particle, ascending id order */
    double scalar_min, scalar_max;
    int draw_walls;             /* outline the mesh walls' sharp and boundary edges, and the planes */
    unsigned char background[3];
} dem_render_def;

DEM_API dem_render_def dem_default_render_def(void); /* 420 x 230 front view, white background */
/* Renders into rgb (width x height x 3 bytes, rows top to bottom). */
DEM_API dem_status dem_render_rgb(dem_domain *domain, const dem_render_def *def, unsigned char *rgb);
DEM_API dem_status dem_render_png(dem_domain *domain, const dem_render_def *def, const char *path);

#ifdef __cplusplus
}
#endif
#endif
