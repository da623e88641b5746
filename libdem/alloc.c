/* Where libdem's memory comes from: the C library's malloc family, or the allocator a host
 * application sets (dem_set_allocator) — every allocation and release of libdem's own arrays
 * goes through here. HDF5 and libpng allocate for themselves while they read and write files. */
#include "internal.h"
#include <stdlib.h>

static dem_allocator alloc = {malloc, calloc, realloc, free};
static int live_objects; /* domains and MLPs: an allocator may change only while none holds memory */

dem_status dem_set_allocator(const dem_allocator *a)
{
    if (live_objects > 0) return DEM_ERR_INVALID_ARGUMENT;
    if (!a) {
        alloc = (dem_allocator){malloc, calloc, realloc, free};
        return DEM_OK;
    }
    if (!a->malloc || !a->calloc || !a->realloc || !a->free) return DEM_ERR_NULL;
    alloc = *a;
    return DEM_OK;
}

void dem_live_objects(int change) { live_objects += change; }

void *dem_malloc(size_t n) { return alloc.malloc(n); }
void *dem_calloc(size_t count, size_t size) { return alloc.calloc(count, size); }
void *dem_realloc(void *p, size_t n) { return alloc.realloc(p, n); }
void dem_free(void *p)
{
    if (p) alloc.free(p);
}
