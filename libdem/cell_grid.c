/* The temporary linked-cell grid of cell_grid.h. */
#include "cell_grid.h"
#include "alloc.h"
#include <stdlib.h>

int cell_grid_alloc(cell_grid *g, int64_t items)
{
    int64_t cells = (int64_t)g->n[0] * g->n[1] * g->n[2];
    g->head = dem_malloc((size_t)cells * sizeof *g->head);
    g->next = dem_malloc((size_t)(items > 0 ? items : 1) * sizeof *g->next);
    if (!g->head || !g->next) {
        cell_grid_free(g);
        return 0;
    }
    for (int64_t c = 0; c < cells; c++) g->head[c] = -1;
    return 1;
}

void cell_grid_free(cell_grid *g)
{
    dem_free(g->head);
    dem_free(g->next);
    g->head = g->next = NULL;
}
