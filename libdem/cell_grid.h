/* Cells of a box for finding near particles: the coordinate of a point (clamped to the grid),
 * a cell's index, and a temporary linked-cell grid (a head per cell, a next per item) for the
 * one-off searches — the overlap check of an insertion (particles.c) and of a new mesh
 * (mesh_cut.c). The neighbour build keeps its own grid in the domain (a counting sort into
 * cell_start, neighbor.c) but places particles with the same cell_clamp. */
#ifndef DEM_CELL_GRID_H
#define DEM_CELL_GRID_H

#include <math.h>
#include <stdint.h>

/* floor'ed coordinate c clamped to [0, n - 1] before the cast (NaN goes to 0) */
static inline int cell_clamp(double c, int n)
{
    if (!(c >= 0.0)) return 0;
    if (c >= n) return n - 1;
    return (int)c;
}

static inline int64_t cell_index(const int n[3], int cx, int cy, int cz)
{
    return ((int64_t)cz * n[1] + cy) * n[0] + cx;
}

typedef struct cell_grid {
    double lo[3], size[3]; /* origin and cell widths */
    int n[3];              /* cells per axis */
    int64_t *head;         /* n[0] n[1] n[2]: the first item of each cell, -1: none */
    int64_t *next;         /* per item: the next item of its cell, -1: the last */
} cell_grid;

/* Allocates head (every cell empty) and next for `items` items; 0: out of memory (nothing held). */
int cell_grid_alloc(cell_grid *g, int64_t items);
void cell_grid_free(cell_grid *g);

static inline int cell_grid_coord(const cell_grid *g, double x, int a)
{
    return cell_clamp(floor((x - g->lo[a]) / g->size[a]), g->n[a]);
}

/* Puts item into cell c; items pushed in descending order come out ascending. */
static inline void cell_grid_push(cell_grid *g, int64_t item, int64_t c)
{
    g->next[item] = g->head[c];
    g->head[c] = item;
}

#endif
