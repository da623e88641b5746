/* libdem — MLP surrogates (seed 000): a tiny inference routine for the one-hidden-layer tanh
 * networks that pydem's nn package trains and exports (nn/export.py documents the weights
 * file, "dem-mlp 1"), and native screening of many parameter combinations with OpenMP.
 *
 * Net: xs = (x - lo) * (2 / (hi - lo)) - 1 per input; z = W1 xs + b1; ys = w2 . tanh(z) + b2;
 * y = (ys + 1) * ((out_hi - out_lo) / 2) + out_lo, then exp(y) when the file says
 * "output_transform log" (a positive quantity learnt as its logarithm; optional, default
 * identity). Inputs and output in physical units.
 * Errors are written to a caller buffer (err, err_size; either may be NULL/0). */
#ifndef DEM_MLP_H
#define DEM_MLP_H
#include "base.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef struct dem_mlp dem_mlp;

/* Reads a "dem-mlp 1" weights file. DEM_ERR_IO (cannot read), DEM_ERR_FORMAT (the message
 * names the line and the keyword), DEM_ERR_NO_MEMORY. */
DEM_API dem_status dem_mlp_load(const char *path, dem_mlp **out, char *err, size_t err_size);
/* The same from text in memory (NUL-terminated). */
DEM_API dem_status dem_mlp_parse(const char *text, dem_mlp **out, char *err, size_t err_size);
/* Writes the net back in the same format (hex floats: an exact round trip). */
DEM_API dem_status dem_mlp_save(const dem_mlp *net, const char *path, char *err, size_t err_size);
DEM_API void dem_mlp_free(dem_mlp *net);

DEM_API const char *dem_mlp_name(const dem_mlp *net);
DEM_API const char *dem_mlp_unit(const dem_mlp *net);          /* "" when dimensionless */
DEM_API int dem_mlp_num_inputs(const dem_mlp *net);
DEM_API int dem_mlp_num_hidden(const dem_mlp *net);
DEM_API const char *dem_mlp_input_name(const dem_mlp *net, int i); /* NULL when out of range */

/* One input vector -> the prediction (libm tanh: the reference path). */
DEM_API double dem_mlp_eval(const dem_mlp *net, const double *x);
/* n input rows (n x inputs, row-major) -> y[n], blocked and vectorised, OpenMP with
 * num_threads (<= 0: the OpenMP default). Agrees with dem_mlp_eval to ~1e-15 relative. */
DEM_API dem_status dem_mlp_eval_many(const dem_mlp *net, const double *x, size_t n, double *y, int num_threads);

/* Screening: evaluates every net on n rows of x (all nets take the same inputs in the same
 * order) and keeps a row when every prediction lies within window[k] x |target[k]| of
 * target[k]. keep[n] (1/0) is filled; predictions (n x num_nets, row-major) when not NULL;
 * *num_kept the count. DEM_ERR_INVALID_ARGUMENT (names the net) when the nets' inputs differ
 * or a target/window is not finite (window must be >= 0). */
DEM_API dem_status dem_mlp_screen(const dem_mlp *const *nets, int num_nets, const double *target, const double *window,
                                  const double *x, size_t n, int num_threads, unsigned char *keep, double *predictions,
                                  size_t *num_kept, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
