/* Status names, version, error messages and small helpers. */
#include "internal.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

const char *dem_status_name(dem_status s)
{
    switch (s) {
    case DEM_OK: return "DEM_OK";
    case DEM_WARN_TIMESTEP_LARGE: return "DEM_WARN_TIMESTEP_LARGE";
    case DEM_ERR_NULL: return "DEM_ERR_NULL";
    case DEM_ERR_INVALID_ARGUMENT: return "DEM_ERR_INVALID_ARGUMENT";
    case DEM_ERR_NO_MEMORY: return "DEM_ERR_NO_MEMORY";
    case DEM_ERR_UNKNOWN_MATERIAL: return "DEM_ERR_UNKNOWN_MATERIAL";
    case DEM_ERR_UNKNOWN_PARTICLE: return "DEM_ERR_UNKNOWN_PARTICLE";
    case DEM_ERR_OVERLAP: return "DEM_ERR_OVERLAP";
    case DEM_ERR_OUT_OF_BOUNDS: return "DEM_ERR_OUT_OF_BOUNDS";
    case DEM_ERR_NUMERICAL: return "DEM_ERR_NUMERICAL";
    case DEM_ERR_RUNAWAY_OVERLAP: return "DEM_ERR_RUNAWAY_OVERLAP";
    case DEM_ERR_UNSTABLE_TIMESTEP: return "DEM_ERR_UNSTABLE_TIMESTEP";
    case DEM_ERR_UNKNOWN_EFFECT: return "DEM_ERR_UNKNOWN_EFFECT";
    case DEM_ERR_UNKNOWN_WALL: return "DEM_ERR_UNKNOWN_WALL";
    case DEM_ERR_IO: return "DEM_ERR_IO";
    case DEM_ERR_FORMAT: return "DEM_ERR_FORMAT";
    case DEM_ERR_UNSUPPORTED: return "DEM_ERR_UNSUPPORTED";
    }
    return "DEM_UNKNOWN_STATUS";
}

void dem_version(int *major, int *minor, int *patch)
{
    if (major) *major = DEM_VERSION_MAJOR;
    if (minor) *minor = DEM_VERSION_MINOR;
    if (patch) *patch = DEM_VERSION_PATCH;
}

const char *dem_version_string(void) { return DEM_VERSION_STRING; }

dem_status dem_fail(dem_domain *d, dem_status s, const char *fmt, ...)
{
    if (!d) return s;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(d->errmsg, sizeof d->errmsg, fmt, ap);
    va_end(ap);
    return s;
}

void dem_clear_error(dem_domain *d) { d->errmsg[0] = '\0'; }

dem_status dem_check_room(const dem_domain *d, int64_t capacity, int64_t count, const char *what, const char *fn)
{
    if (capacity >= count) return DEM_OK;
    return dem_fail((dem_domain *)d, DEM_ERR_INVALID_ARGUMENT, "%s: room for %lld %s, %lld to write", fn,
                    (long long)capacity, what, (long long)count);
}

const char *dem_domain_last_error(const dem_domain *d) { return d ? d->errmsg : "domain is NULL"; }

void *dem_realloc_array(void *p, size_t count, size_t elem)
{
    if (count == 0) count = 1;
    if (count > SIZE_MAX / elem) return NULL;
    return dem_realloc(p, count * elem);
}

int dem_reserve_rows(int64_t **start, int64_t *cap, int64_t n)
{
    if (*start && n + 1 <= *cap) return 1;
    const int64_t c = n + 1 + (n + 1) / 2;
    int64_t *s = dem_realloc_array(*start, (size_t)c, sizeof *s);
    if (!s) return 0;
    *start = s;
    *cap = c;
    return 1;
}

int dem_realloc_all(void **arrays[], int n_arrays, size_t count, size_t elem)
{
    int ok = 1;
    for (int a = 0; a < n_arrays; a++) {
        void *q = dem_realloc_array(*arrays[a], count, elem);
        if (q) *arrays[a] = q;
        else ok = 0;
    }
    return ok;
}

int dem_is_finite(double x) { return isfinite(x) ? 1 : 0; }

static dem_assert_hook assert_hook; /* process-wide, like an allocator: set once, before the runs */

void dem_set_assert_hook(dem_assert_hook hook) { assert_hook = hook; }

void dem_assert_fail(const char *expr, const char *file, int line)
{
    if (assert_hook) {
        assert_hook(expr, file, line);
        return;
    }
    fprintf(stderr, "libdem: internal invariant broken: %s (%s:%d)\n", expr, file, line);
    abort();
}
