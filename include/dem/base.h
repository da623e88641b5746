/* libdem — base definitions: version, status codes, export macro.
 * Units are SI everywhere (m, kg, s, N, Pa, rad). */
#ifndef DEM_BASE_H
#define DEM_BASE_H

#include <stddef.h>
#include <stdint.h>

#define DEM_VERSION_MAJOR 0
#define DEM_VERSION_MINOR 2
#define DEM_VERSION_PATCH 1
#define DEM_VERSION_STRING "0.2.1"

#if defined(_WIN32) && defined(DEM_BUILD_SHARED)
#define DEM_API __declspec(dllexport)
#elif defined(__GNUC__)
#define DEM_API __attribute__((visibility("default")))
#else
#define DEM_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Status of every fallible call. Values are fixed and never renumbered.
 * 0 is success, positive values are warnings (the call did its work),
 * negative values are errors (the call did nothing, or stopped and says why).
 * The words behind the last status live on the domain: dem_domain_last_error(). */
typedef enum dem_status {
    DEM_OK = 0,
    DEM_WARN_TIMESTEP_LARGE = 1,  /* dt above 20 % of the Rayleigh time; stepped anyway */

    DEM_ERR_NULL = -1,             /* a required pointer was NULL */
    DEM_ERR_INVALID_ARGUMENT = -2, /* NaN, negative, out-of-range value */
    DEM_ERR_NO_MEMORY = -3,
    DEM_ERR_UNKNOWN_MATERIAL = -4,
    DEM_ERR_UNKNOWN_PARTICLE = -5,
    DEM_ERR_OVERLAP = -6,          /* insertion overlaps a particle or a wall */
    DEM_ERR_OUT_OF_BOUNDS = -7,    /* particle outside the domain on a closed axis */
    DEM_ERR_NUMERICAL = -8,        /* NaN/inf appeared in the state */
    DEM_ERR_RUNAWAY_OVERLAP = -9,  /* overlap beyond max_overlap_ratio: dt too large or E too small */
    DEM_ERR_UNSTABLE_TIMESTEP = -10, /* dt above the Rayleigh time: refused */
    DEM_ERR_UNKNOWN_EFFECT = -11,
    DEM_ERR_UNKNOWN_WALL = -12,
    DEM_ERR_IO = -13,
    DEM_ERR_FORMAT = -14,
    DEM_ERR_UNSUPPORTED = -15      /* a feature this build left out (make HDF5=0 or PNG=0) */
} dem_status;

/* Called when an internal invariant fails in a checking build (-DDEM_CHECKS): the expression,
 * file and line. NULL (the default) prints them to stderr and aborts. */
typedef void (*dem_assert_hook)(const char *expression, const char *file, int line);
DEM_API void dem_set_assert_hook(dem_assert_hook hook);

/* Where libdem's memory comes from (process-wide): the C library's malloc family by default.
 * A host application may set its own before it creates a domain (or after destroying the
 * last one): DEM_ERR_INVALID_ARGUMENT while any domain exists, DEM_ERR_NULL for a missing
 * function; NULL restores the default. HDF5 and libpng allocate for themselves in file I/O. */
typedef struct dem_allocator {
    void *(*malloc)(size_t size);
    void *(*calloc)(size_t count, size_t size);
    void *(*realloc)(void *p, size_t size);
    void (*free)(void *p);
} dem_allocator;
DEM_API dem_status dem_set_allocator(const dem_allocator *allocator);

/* Short fixed name of a status ("DEM_ERR_OVERLAP"); never NULL. */
DEM_API const char *dem_status_name(dem_status status);

/* Run-time version; compare with the DEM_VERSION_* macros to detect a mismatch. */
DEM_API void dem_version(int *major, int *minor, int *patch);
DEM_API const char *dem_version_string(void);

#ifdef __cplusplus
}
#endif
#endif
