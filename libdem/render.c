/* Orthographic rendering of the spheres (z-buffered shaded discs) and the walls' outlines
 * into an RGB buffer or a PNG file. */
#include "internal.h"
#include <float.h>
#include <math.h>
#ifndef DEM_NO_PNG
#include <png.h>
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

dem_render_def dem_default_render_def(void)
{
    dem_render_def r;
    memset(&r, 0, sizeof r);
    r.width = 420; /* seed 001's front views */
    r.height = 230;
    r.view_axis = 1;
    r.color_mode = DEM_COLOR_MATERIAL;
    r.scalar_max = 1.0;
    r.draw_walls = 1;
    r.background[0] = r.background[1] = r.background[2] = 255;
    return r;
}

static const unsigned char palette[10][3] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44}, {214, 39, 40}, {148, 103, 189},
                                             {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
static const unsigned char grey_levels[4] = {70, 150, 110, 190};

/* blue -> cyan -> green -> yellow -> red for s in [0, 1] */
static void colormap(double s, unsigned char *c)
{
    static const double stops[5][3] = {{0, 0, 255}, {0, 200, 255}, {0, 190, 0}, {255, 220, 0}, {220, 0, 0}};
    if (!(s > 0.0)) s = 0.0; /* NaN -> low end */
    if (s > 1.0) s = 1.0;
    double p = s * 4.0;
    int k = p >= 4.0 ? 3 : (int)p;
    double t = p - k;
    for (int a = 0; a < 3; a++) c[a] = (unsigned char)(stops[k][a] + t * (stops[k + 1][a] - stops[k][a]) + 0.5);
}

typedef struct view {
    int w, h, ax_u, ax_v, ax_d; /* image right, image up, depth */
    double lo[2], hi[2], sx, sy; /* pixels per metre */
} view;

static void set_pixel(unsigned char *rgb, const view *v, int x, int y, const unsigned char *c)
{
    if (x < 0 || y < 0 || x >= v->w || y >= v->h) return;
    memcpy(rgb + 3 * ((size_t)y * v->w + x), c, 3);
}

/* A line between two points given in metres (image coordinates). */
static void draw_line(unsigned char *rgb, const view *v, double u0, double v0, double u1, double v1, const unsigned char *c)
{
    double x0 = (u0 - v->lo[0]) * v->sx, y0 = (v->hi[1] - v0) * v->sy, x1 = (u1 - v->lo[0]) * v->sx, y1 = (v->hi[1] - v1) * v->sy;
    double len = fmax(fabs(x1 - x0), fabs(y1 - y0));
    if (!(len < 1e5)) return; /* far outside (or NaN): skip */
    int n = (int)len + 1;
    for (int k = 0; k <= n; k++) {
        double t = (double)k / n;
        set_pixel(rgb, v, (int)floor(x0 + t * (x1 - x0)), (int)floor(y0 + t * (y1 - y0)), c);
    }
}

static void draw_walls(const dem_domain *d, unsigned char *rgb, const view *v)
{
    const unsigned char c[3] = {40, 40, 40};
    for (int w = 0; w < d->n_walls; w++) { /* planes seen edge-on are lines */
        const dem_plane_wall_def *p = &d->walls[w].def;
        if (p->axis == v->ax_u) draw_line(rgb, v, p->position, v->lo[1], p->position, v->hi[1], c);
        if (p->axis == v->ax_v) draw_line(rgb, v, v->lo[0], p->position, v->hi[0], p->position, c);
    }
    for (int k = 0; k < d->n_meshes; k++) { /* boundary edges and sharp (> 20 degree) edges */
        const mesh_wall *m = &d->meshes[k];
        int32_t *first = dem_malloc((size_t)m->ne * 2 * sizeof(int32_t) + 8);
        if (!first) return;
        int32_t *second = first + m->ne;
        for (int64_t e = 0; e < m->ne; e++) first[e] = second[e] = -1;
        for (int64_t t = 0; t < m->nt; t++)
            for (int q = 0; q < 3; q++) {
                int32_t e = m->tri_edge[3 * t + q];
                if (first[e] < 0) first[e] = (int32_t)t;
                else second[e] = (int32_t)t;
            }
        for (int64_t t = 0; t < m->nt; t++)
            for (int q = 0; q < 3; q++) {
                int32_t e = m->tri_edge[3 * t + q];
                if (first[e] != t) continue; /* each edge once */
                int sharp = second[e] < 0;
                if (!sharp) {
                    const double *n0 = m->normal + 3 * t, *n1 = m->normal + 3 * (int64_t)second[e];
                    sharp = fabs(n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2]) < 0.94;
                }
                if (!sharp) continue;
                const double *a = m->x + 3 * m->tri[3 * t + q], *b = m->x + 3 * m->tri[3 * t + (q + 1) % 3];
                draw_line(rgb, v, a[v->ax_u], a[v->ax_v], b[v->ax_u], b[v->ax_v], c);
            }
        dem_free(first);
    }
}

dem_status dem_render_rgb(dem_domain *d, const dem_render_def *def, unsigned char *rgb)
{
    const char *fn = "dem_render_rgb";
    if (!d) return DEM_ERR_NULL;
    if (!def || !rgb) return dem_fail(d, DEM_ERR_NULL, "%s: def and rgb must not be NULL", fn);
    if (def->width < 1 || def->height < 1 || def->width > 16384 || def->height > 16384)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: image size must be 1..16384 pixels, got %d x %d", fn, def->width,
                        def->height);
    if (def->view_axis < 0 || def->view_axis > 2)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: view_axis must be 0, 1 or 2", fn);
    if (def->color_mode == DEM_COLOR_SCALAR && !def->scalar)
        return dem_fail(d, DEM_ERR_NULL, "%s: DEM_COLOR_SCALAR needs the scalar array", fn);
    if ((int)def->color_mode < 0 || (int)def->color_mode > 2)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: unknown colour mode %d", fn, (int)def->color_mode);
    view v;
    v.w = def->width;
    v.h = def->height;
    v.ax_d = def->view_axis;
    v.ax_u = def->view_axis == 0 ? 1 : 0;
    v.ax_v = def->view_axis == 2 ? 1 : 2;
    int auto_window = !(def->hi[0] > def->lo[0]) || !(def->hi[1] > def->lo[1]);
    for (int k = 0; k < 2; k++) {
        int ax = k == 0 ? v.ax_u : v.ax_v;
        v.lo[k] = auto_window ? d->def.lo[ax] : def->lo[k];
        v.hi[k] = auto_window ? d->def.hi[ax] : def->hi[k];
        if (!dem_is_finite(v.lo[k]) || !dem_is_finite(v.hi[k]))
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: the window must be finite", fn);
    }
    v.sx = v.w / (v.hi[0] - v.lo[0]);
    v.sy = v.h / (v.hi[1] - v.lo[1]);
    float *depth = dem_malloc((size_t)v.w * v.h * sizeof(float));
    double *value = NULL;
    if (def->color_mode == DEM_COLOR_SCALAR) value = dem_malloc((size_t)(d->n + 1) * sizeof(double));
    if (!depth || (def->color_mode == DEM_COLOR_SCALAR && !value)) {
        dem_free(depth);
        dem_free(value);
        return dem_fail(d, DEM_ERR_NO_MEMORY, "%s: out of memory", fn);
    }
    if (value) { /* the caller's array is in ascending id order */
        int64_t rank = 0;
        for (dem_particle_id id = 0; id < d->next_id; id++)
            if (d->index_of_id[id] >= 0) value[d->index_of_id[id]] = def->scalar[rank++];
    }
    for (size_t p = 0; p < (size_t)v.w * v.h; p++) {
        depth[p] = FLT_MAX;
        memcpy(rgb + 3 * p, def->background, 3);
    }
    const double span = def->scalar_max - def->scalar_min;
    for (int64_t i = 0; i < d->n; i++) {
        const double *x = d->x + 3 * i, r = d->radius[i];
        const double px = (x[v.ax_u] - v.lo[0]) * v.sx, py = (v.hi[1] - x[v.ax_v]) * v.sy;
        const double rx = r * v.sx, ry = r * v.sy;
        int x0 = (int)floor(px - rx), x1 = (int)ceil(px + rx), y0 = (int)floor(py - ry), y1 = (int)ceil(py + ry);
        if (x1 < 0 || y1 < 0 || x0 >= v.w || y0 >= v.h) continue;
        if (x0 < 0) x0 = 0;
        if (y0 < 0) y0 = 0;
        if (x1 >= v.w) x1 = v.w - 1;
        if (y1 >= v.h) y1 = v.h - 1;
        unsigned char base[3];
        if (def->color_mode == DEM_COLOR_SCALAR) colormap(span != 0.0 ? (value[i] - def->scalar_min) / span : 0.5, base);
        else if (def->color_mode == DEM_COLOR_GREY) memset(base, grey_levels[d->mat[i] % 4], 3);
        else memcpy(base, palette[d->mat[i] % 10], 3);
        for (int py_ = y0; py_ <= y1; py_++) {
            const double dy = (py_ + 0.5 - py) / ry;
            for (int px_ = x0; px_ <= x1; px_++) {
                const double dx = (px_ + 0.5 - px) / rx, q = dx * dx + dy * dy;
                if (q > 1.0) continue;
                const double h = sqrt(1.0 - q);
                const float z = (float)(x[v.ax_d] - r * h); /* the sphere's front surface */
                float *zb = depth + (size_t)py_ * v.w + px_;
                if (z >= *zb) continue;
                *zb = z;
                /* light from the viewer, a little from the upper left */
                double shade = 0.45 + 0.55 * fmax(0.0, 0.8 * h - 0.35 * dx - 0.35 * dy + 0.2);
                if (shade > 1.0) shade = 1.0;
                unsigned char *c = rgb + 3 * ((size_t)py_ * v.w + px_);
                for (int a = 0; a < 3; a++) c[a] = (unsigned char)(base[a] * shade + 0.5);
            }
        }
    }
    if (def->draw_walls) draw_walls(d, rgb, &v);
    dem_free(depth);
    dem_free(value);
    dem_clear_error(d);
    return DEM_OK;
}

#ifndef DEM_NO_PNG
/* 1 on success; libpng reports its errors by longjmp, so nothing here changes after setjmp. */
static int write_png(FILE *fp, const unsigned char *rgb, int w, int h)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    png_bytep *rows = dem_malloc((size_t)h * sizeof *rows);
    if (!png || !info || !rows) {
        png_destroy_write_struct(&png, &info);
        dem_free(rows);
        return 0;
    }
    for (int y = 0; y < h; y++) rows[y] = (png_bytep)(rgb + (size_t)y * w * 3);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        dem_free(rows);
        return 0;
    }
    png_init_io(png, fp);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 3); /* fast: frames are written often */
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    dem_free(rows);
    return 1;
}

#endif

dem_status dem_render_png(dem_domain *d, const dem_render_def *def, const char *path)
{
    if (!d) return DEM_ERR_NULL;
#ifdef DEM_NO_PNG /* a build without libpng (make PNG=0) */
    (void)def;
    (void)path;
    return dem_fail(d, DEM_ERR_UNSUPPORTED,
                    "dem_render_png: this libdem was built without libpng (make PNG=0); dem_render_rgb gives the pixels");
#else
    if (!def || !path) return dem_fail(d, DEM_ERR_NULL, "dem_render_png: def and path must not be NULL");
    if (def->width < 1 || def->height < 1 || def->width > 16384 || def->height > 16384)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_render_png: image size must be 1..16384 pixels, got %d x %d",
                        def->width, def->height);
    unsigned char *rgb = dem_malloc((size_t)def->width * def->height * 3);
    if (!rgb) return dem_fail(d, DEM_ERR_NO_MEMORY, "dem_render_png: out of memory");
    dem_status s = dem_render_rgb(d, def, rgb);
    if (s != DEM_OK) {
        dem_free(rgb);
        return s;
    }
    FILE *fp = fopen(path, "wb");
    if (!fp) {
        dem_free(rgb);
        return dem_fail(d, DEM_ERR_IO, "dem_render_png: cannot create '%s'", path);
    }
    int ok = write_png(fp, rgb, def->width, def->height);
    dem_free(rgb);
    ok = (fclose(fp) == 0) && ok;
    if (!ok) return dem_fail(d, DEM_ERR_IO, "dem_render_png: writing '%s' failed", path);
    dem_clear_error(d);
    return DEM_OK;
#endif
}
