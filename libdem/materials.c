/* Materials, material pairs and their derived contact constants. */
#include "internal.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

dem_material_def dem_default_material_def(void)
{
    dem_material_def m;
    m.youngs_modulus = 5e6;
    m.poisson_ratio = 0.25;
    m.density = 2500.0;
    m.shear_modulus = 0.0;
    return m;
}

dem_pair_def dem_default_pair_def(void)
{
    dem_pair_def p;
    p.restitution = 0.5;
    p.friction = 0.5;
    p.rolling_friction = 0.0;
    p.rolling_model = DEM_ROLLING_EPSD2;
    p.rolling_damping = 0.0;
    return p;
}

const pair_props *dem_pair_props(const dem_domain *d, int a, int b)
{
    return &d->pairs[(size_t)a * d->n_materials + b];
}

/* (2 - nu) / G of a material: its share of 1 / G*. The isotropic form keeps the expression in E
 * it always had (the same rounding: results of isotropic materials are bitwise those before G
 * could be given). */
static double shear_compliance(const dem_material_def *m)
{
    if (m->shear_modulus > 0.0) return (2 - m->poisson_ratio) / m->shear_modulus;
    return 2 * (2 - m->poisson_ratio) * (1 + m->poisson_ratio) / m->youngs_modulus;
}

double dem_material_shear_modulus(const dem_material_def *m)
{
    return m->shear_modulus > 0.0 ? m->shear_modulus : m->youngs_modulus / (2.0 * (1.0 + m->poisson_ratio));
}

/* Recompute E*, G*, damping of pair (a, b) and its mirror from the materials and def. */
void dem_pair_recompute(dem_domain *d, int a, int b)
{
    pair_props *p = &d->pairs[(size_t)a * d->n_materials + b];
    const dem_material_def *ma = &d->materials[a], *mb = &d->materials[b];
    p->e_star = 1.0 / ((1 - ma->poisson_ratio * ma->poisson_ratio) / ma->youngs_modulus +
                       (1 - mb->poisson_ratio * mb->poisson_ratio) / mb->youngs_modulus);
    p->g_star = 1.0 / (shear_compliance(ma) + shear_compliance(mb));
    p->damping_factor = dem_damping_factor_for_restitution(p->def.restitution);
    p->st_over_sn_sqrt = sqrt(4.0 * p->g_star / p->e_star);
    d->pairs[(size_t)b * d->n_materials + a] = *p;
}

static dem_status check_material(dem_domain *d, const dem_material_def *m)
{
    if (!dem_is_finite(m->youngs_modulus) || m->youngs_modulus <= 0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "material: Young's modulus must be finite and > 0 Pa, got %g",
                        m->youngs_modulus);
    if (!dem_is_finite(m->poisson_ratio) || m->poisson_ratio <= -1.0 || m->poisson_ratio >= 0.5)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "material: Poisson ratio must be in (-1, 0.5), got %g",
                        m->poisson_ratio);
    if (!dem_is_finite(m->shear_modulus) || m->shear_modulus < 0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT,
                        "material: shear modulus must be finite and > 0 Pa (or 0: E / (2 (1 + nu))), got %g",
                        m->shear_modulus);
    if (!dem_is_finite(m->density) || m->density <= 0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "material: density must be finite and > 0 kg/m^3, got %g",
                        m->density);
    return DEM_OK;
}

dem_status dem_material_create(dem_domain *d, const dem_material_def *def, dem_material *material)
{
    if (!d) return DEM_ERR_NULL;
    if (!def || !material) return dem_fail(d, DEM_ERR_NULL, "dem_material_create: def and material must not be NULL");
    dem_status s = check_material(d, def);
    if (s != DEM_OK) return s;
    int n_old = d->n_materials, n = n_old + 1;
    dem_material_def *mats = dem_realloc_array(NULL, (size_t)n, sizeof *mats);
    pair_props *pairs = dem_realloc_array(NULL, (size_t)n * n, sizeof *pairs);
    if (!mats || !pairs) {
        dem_free(mats);
        dem_free(pairs);
        return dem_fail(d, DEM_ERR_NO_MEMORY, "dem_material_create: out of memory");
    }
    if (n_old) memcpy(mats, d->materials, (size_t)n_old * sizeof *mats);
    mats[n_old] = *def;
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) {
            pair_props *p = &pairs[(size_t)a * n + b];
            if (a < n_old && b < n_old) {
                *p = d->pairs[(size_t)a * n_old + b];
            } else {
                memset(p, 0, sizeof *p);
                p->def = dem_default_pair_def();
            }
        }
    dem_free(d->materials);
    dem_free(d->pairs);
    d->materials = mats;
    d->pairs = pairs;
    d->n_materials = n;
    for (int a = 0; a < n; a++) dem_pair_recompute(d, a, n_old);
    d->rayleigh_cache = -1.0;
    material->index = n_old;
    dem_clear_error(d);
    return DEM_OK;
}

int dem_material_count(const dem_domain *d) { return d ? d->n_materials : 0; }

static dem_status check_pair_ids(dem_domain *d, int a, int b, const char *fn)
{
    if (a < 0 || a >= d->n_materials || b < 0 || b >= d->n_materials)
        return dem_fail(d, DEM_ERR_UNKNOWN_MATERIAL, "%s: unknown material pair (%d, %d); %d materials exist", fn, a, b,
                        d->n_materials);
    return DEM_OK;
}

dem_status dem_pair_set(dem_domain *d, dem_material a_material, dem_material b_material, const dem_pair_def *def)
{
    const int a = a_material.index, b = b_material.index;
    if (!d) return DEM_ERR_NULL;
    if (!def) return dem_fail(d, DEM_ERR_NULL, "dem_pair_set: def must not be NULL");
    dem_status s = check_pair_ids(d, a, b, "dem_pair_set");
    if (s != DEM_OK) return s;
    if (!dem_is_finite(def->restitution) || def->restitution <= 0.0 || def->restitution > 1.0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_pair_set: restitution must be in (0, 1], got %g",
                        def->restitution);
    if (!dem_is_finite(def->friction) || def->friction < 0.0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_pair_set: sliding friction must be finite and >= 0, got %g",
                        def->friction);
    if (!dem_is_finite(def->rolling_friction) || def->rolling_friction < 0.0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_pair_set: rolling friction must be finite and >= 0, got %g",
                        def->rolling_friction);
    if (def->rolling_model != DEM_ROLLING_CDT && def->rolling_model != DEM_ROLLING_EPSD &&
        def->rolling_model != DEM_ROLLING_EPSD2)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_pair_set: unknown rolling model %d (CDT 0, EPSD 1, EPSD2 2)",
                        (int)def->rolling_model);
    if (!dem_is_finite(def->rolling_damping) || def->rolling_damping < 0.0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_pair_set: rolling damping must be finite and >= 0, got %g",
                        def->rolling_damping);
    pair_props *p = &d->pairs[(size_t)a * d->n_materials + b];
    p->def = *def;
    dem_pair_recompute(d, a, b);
    d->forces_valid = 0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_pair_get(const dem_domain *d, dem_material a_material, dem_material b_material, dem_pair_def *def)
{
    const int a = a_material.index, b = b_material.index;
    if (!d || !def) return DEM_ERR_NULL;
    if (a < 0 || a >= d->n_materials || b < 0 || b >= d->n_materials) return DEM_ERR_UNKNOWN_MATERIAL;
    *def = dem_pair_props(d, a, b)->def;
    return DEM_OK;
}

dem_status dem_pair_damping_factor(const dem_domain *d, dem_material a_material, dem_material b_material, double *factor)
{
    const int a = a_material.index, b = b_material.index;
    if (!d || !factor) return DEM_ERR_NULL;
    if (a < 0 || a >= d->n_materials || b < 0 || b >= d->n_materials) return DEM_ERR_UNKNOWN_MATERIAL;
    *factor = dem_pair_props(d, a, b)->damping_factor;
    return DEM_OK;
}

dem_status dem_pair_set_effect(dem_domain *d, dem_material a_material, dem_material b_material, const char *effect, const double *params, int n_params)
{
    const int a = a_material.index, b = b_material.index;
    if (!d) return DEM_ERR_NULL;
    if (!effect) return dem_fail(d, DEM_ERR_NULL, "dem_pair_set_effect: effect name must not be NULL");
    dem_status s = check_pair_ids(d, a, b, "dem_pair_set_effect");
    if (s != DEM_OK) return s;
    int idx = dem_effect_find(effect);
    if (idx < 0) return dem_fail(d, DEM_ERR_UNKNOWN_EFFECT, "dem_pair_set_effect: no effect named '%s'", effect);
    const dem_effect_desc *e = dem_effect_get(idx);
    if (n_params != e->n_params || (n_params > 0 && !params))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_pair_set_effect: effect '%s' takes %d parameters, got %d",
                        effect, e->n_params, n_params);
    int neutral = 1;
    for (int k = 0; k < n_params; k++) {
        const dem_effect_param *pd = &e->params[k];
        if (!dem_is_finite(params[k]) || params[k] < pd->min || params[k] > pd->max)
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_pair_set_effect: %s.%s must be in [%g, %g] %s, got %g",
                            effect, pd->name, pd->min, pd->max, pd->unit, params[k]);
        if (params[k] != pd->neutral) neutral = 0;
    }
    pair_props *p = &d->pairs[(size_t)a * d->n_materials + b];
    int slot = -1;
    for (int k = 0; k < p->n_effects; k++)
        if (p->effects[k].effect == idx) slot = k;
    if (neutral) { /* switch off: drop the slot */
        if (slot >= 0) {
            for (int k = slot; k + 1 < p->n_effects; k++) p->effects[k] = p->effects[k + 1];
            p->n_effects--;
        }
    } else {
        if (slot < 0) {
            if (p->n_effects >= DEM_MAX_EFFECTS_PER_PAIR)
                return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_pair_set_effect: at most %d effects per pair",
                                DEM_MAX_EFFECTS_PER_PAIR);
            slot = p->n_effects++;
        }
        p->effects[slot].effect = idx;
        for (int k = 0; k < DEM_MAX_EFFECT_PARAMS; k++) p->effects[slot].params[k] = k < n_params ? params[k] : 0.0;
    }
    d->pairs[(size_t)b * d->n_materials + a] = *p;
    d->forces_valid = 0;
    dem_clear_error(d);
    return DEM_OK;
}
