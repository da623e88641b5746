/* libdem's memory (alloc.c): from the allocator of dem_set_allocator, the C library's by
 * default. dem_live_objects(+1 / -1) as domains and MLPs are created and freed: the allocator
 * may change only while none holds memory. */
#ifndef DEM_ALLOC_H
#define DEM_ALLOC_H

#include <stddef.h>

void *dem_malloc(size_t n);
void *dem_calloc(size_t count, size_t size);
void *dem_realloc(void *p, size_t n);
void dem_free(void *p);
void dem_live_objects(int change);

#endif
