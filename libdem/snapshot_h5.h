/* Shared by the snapshot writer and reader (internal). */
#ifndef DEM_SNAPSHOT_H5_H
#define DEM_SNAPSHOT_H5_H

#include "internal.h"
#include <hdf5.h>
#include <stdio.h>

#define FORMAT_NAME "libdem snapshot"
#define FORMAT_VERSION 1

#endif
