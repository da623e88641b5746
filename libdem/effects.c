/* The effect registry: optional physics selectable by name (DESIGN section 4).
 * To add an effect: write effect_<name>.c with its kernel and descriptor, add one row to
 * the table below, add one analytic test. See docs/effects.md. */
#include "internal.h"
#include <string.h>

extern const dem_effect_desc dem_effect_cohesion_sjkr;
extern const dem_effect_desc dem_effect_twisting_resistance;

static const dem_effect_desc *const registry[] = {
    &dem_effect_cohesion_sjkr,
    &dem_effect_twisting_resistance,
};

#define N_EFFECTS ((int)(sizeof registry / sizeof registry[0]))

const dem_effect_desc *dem_effect_get(int index)
{
    return (index >= 0 && index < N_EFFECTS) ? registry[index] : NULL;
}

int dem_effect_find(const char *name)
{
    for (int i = 0; i < N_EFFECTS; i++)
        if (strcmp(registry[i]->name, name) == 0) return i;
    return -1;
}

int dem_effect_count(void) { return N_EFFECTS; }

dem_status dem_effect_info(int index, const char **name, const char **summary, int *n_params)
{
    const dem_effect_desc *e = dem_effect_get(index);
    if (!e) return DEM_ERR_UNKNOWN_EFFECT;
    if (name) *name = e->name;
    if (summary) *summary = e->summary;
    if (n_params) *n_params = e->n_params;
    return DEM_OK;
}

dem_status dem_effect_param_info(int index, int param, const char **name, const char **unit,
                                 double *neutral)
{
    const dem_effect_desc *e = dem_effect_get(index);
    if (!e) return DEM_ERR_UNKNOWN_EFFECT;
    if (param < 0 || param >= e->n_params) return DEM_ERR_INVALID_ARGUMENT;
    if (name) *name = e->params[param].name;
    if (unit) *unit = e->params[param].unit;
    if (neutral) *neutral = e->params[param].neutral;
    return DEM_OK;
}

dem_status dem_effect_param_range(int index, int param, double *min, double *max)
{
    const dem_effect_desc *e = dem_effect_get(index);
    if (!e) return DEM_ERR_UNKNOWN_EFFECT;
    if (param < 0 || param >= e->n_params) return DEM_ERR_INVALID_ARGUMENT;
    if (min) *min = e->params[param].min;
    if (max) *max = e->params[param].max;
    return DEM_OK;
}
