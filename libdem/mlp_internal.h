/* libdem internal: the MLP struct shared by mlp.c (files, reference evaluation) and
 * mlp_screen.c (blocked evaluation and screening). */
#ifndef DEM_MLP_INTERNAL_H
#define DEM_MLP_INTERNAL_H
#include "dem/mlp.h"

#define DEM_MLP_NAME_MAX 64
#define DEM_MLP_MAX_INPUTS 64
#define DEM_MLP_MAX_HIDDEN 4096

struct dem_mlp {
    char name[DEM_MLP_NAME_MAX];
    char unit[DEM_MLP_NAME_MAX];
    char input_names[DEM_MLP_MAX_INPUTS][DEM_MLP_NAME_MAX];
    int nin, nhid;
    double in_lo[DEM_MLP_MAX_INPUTS], in_hi[DEM_MLP_MAX_INPUTS];
    double out_lo, out_hi, b2;
    int out_log; /* output_transform log: y = exp(scaled output) (a positive quantity learnt as its log) */
    double *w1; /* nhid x nin */
    double *b1; /* nhid */
    double *w2; /* nhid */
};

void dem_mlp_set_error(char *err, size_t err_size, const char *fmt, ...);

#endif
