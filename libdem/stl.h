/* STL reader (internal): file or buffer -> triangle soup. */
#ifndef DEM_STL_H
#define DEM_STL_H

#include <stddef.h>
#include <stdint.h>

enum { STL_OK = 0, STL_IO = 1, STL_BAD = 2, STL_NO_MEMORY = 3 };

typedef struct stl_soup {
    double *xyz; /* 9 per triangle: three vertices; malloc'ed, caller frees */
    int64_t n;
} stl_soup;

/* Parses a whole STL file held in memory. On failure out->xyz is NULL and err says why. */
int dem_stl_parse(const unsigned char *buf, size_t len, stl_soup *out, char *err, size_t errsz);
int dem_stl_read_file(const char *path, stl_soup *out, char *err, size_t errsz);

#endif
