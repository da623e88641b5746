/* MLP weights files ("dem-mlp 1", written by pydem nn/export.py) and the reference evaluation. */
#include "mlp_internal.h"
#include "alloc.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void dem_mlp_set_error(char *err, size_t err_size, const char *fmt, ...)
{
    va_list ap;
    if (!err || err_size == 0)
        return;
    va_start(ap, fmt);
    vsnprintf(err, err_size, fmt, ap);
    va_end(ap);
}

void dem_mlp_free(dem_mlp *net)
{
    if (!net)
        return;
    dem_free(net->w1);
    dem_free(net->b1);
    dem_free(net->w2);
    dem_free(net);
    dem_live_objects(-1);
}

/* Reads exactly `count` numbers from the rest of a line; strtod reads C99 hex floats exactly. */
static int read_numbers(const char *s, double *dst, int count, int line, const char *key, char *err, size_t err_size)
{
    int k;
    for (k = 0; k < count; ++k) {
        char *end;
        errno = 0;
        dst[k] = strtod(s, &end);
        if (end == s) {
            dem_mlp_set_error(err, err_size, "line %d (%s): expected %d numbers, found %d", line, key, count, k);
            return 0;
        }
        if (!isfinite(dst[k])) {
            dem_mlp_set_error(err, err_size, "line %d (%s): value %d is not finite", line, key, k + 1);
            return 0;
        }
        s = end;
    }
    while (*s == ' ' || *s == '\t' || *s == '\r')
        ++s;
    if (*s != '\0') {
        dem_mlp_set_error(err, err_size, "line %d (%s): more than the %d expected numbers", line, key, count);
        return 0;
    }
    return 1;
}

static int copy_word(char *dst, const char *src, size_t len, int line, const char *key, char *err, size_t err_size)
{
    if (len == 0 || len >= DEM_MLP_NAME_MAX) {
        dem_mlp_set_error(err, err_size, "line %d (%s): missing or longer than %d characters", line, key,
                          DEM_MLP_NAME_MAX - 1);
        return 0;
    }
    memcpy(dst, src, len);
    dst[len] = '\0';
    return 1;
}

enum { F_MAGIC = 1, F_NAME = 2, F_UNIT = 4, F_INPUTS = 8, F_HIDDEN = 16, F_INLO = 32, F_INHI = 64, F_OUTLO = 128,
       F_OUTHI = 256, F_W1 = 512, F_B1 = 1024, F_W2 = 2048, F_B2 = 4096, F_ALL = 8191 /* required */,
       F_TRANSFORM = 8192 /* optional */ };

static const char *field_names[] = {"dem-mlp", "name", "unit", "inputs", "hidden", "input_lo", "input_hi",
                                    "output_lo", "output_hi", "w1", "b1", "w2", "b2", "output_transform"};

/* One keyword line; returns the field bit it set, 0 on error (message written). */
static int parse_line(dem_mlp *m, const char *key, size_t klen, const char *rest, int seen, int line, char *err,
                      size_t err_size)
{
    int f;
    for (f = 0; f < 14; ++f)
        if (strlen(field_names[f]) == klen && strncmp(key, field_names[f], klen) == 0)
            break;
    if (f == 14) {
        dem_mlp_set_error(err, err_size, "line %d: unknown keyword '%.*s'", line, (int)klen, key);
        return 0;
    }
    if (seen & (1 << f)) {
        dem_mlp_set_error(err, err_size, "line %d: '%s' appears twice", line, field_names[f]);
        return 0;
    }
    if (f > 0 && !(seen & F_MAGIC)) {
        dem_mlp_set_error(err, err_size, "line %d: the file must start with 'dem-mlp 1'", line);
        return 0;
    }
    if (f >= 5 && !((seen & F_INPUTS) && (seen & F_HIDDEN))) {
        dem_mlp_set_error(err, err_size, "line %d (%s): 'inputs' and 'hidden' must come first", line, field_names[f]);
        return 0;
    }
    switch (f) {
    case 0: {
        double v;
        if (!read_numbers(rest, &v, 1, line, "dem-mlp", err, err_size))
            return 0;
        if (v != 1.0) {
            dem_mlp_set_error(err, err_size, "line %d: format version %g, this libdem reads version 1", line, v);
            return 0;
        }
        break;
    }
    case 1:
    case 2: {
        size_t len = strcspn(rest, " \t\r");
        if (!copy_word(f == 1 ? m->name : m->unit, rest, len, line, field_names[f], err, err_size))
            return 0;
        if (f == 2 && strcmp(m->unit, "-") == 0)
            m->unit[0] = '\0';
        break;
    }
    case 3: {
        char *end;
        long nin = strtol(rest, &end, 10);
        int i;
        if (end == rest || nin < 1 || nin > DEM_MLP_MAX_INPUTS) {
            dem_mlp_set_error(err, err_size, "line %d (inputs): count must be 1..%d", line, DEM_MLP_MAX_INPUTS);
            return 0;
        }
        m->nin = (int)nin;
        for (i = 0; i < m->nin; ++i) {
            size_t len;
            while (*end == ' ' || *end == '\t')
                ++end;
            len = strcspn(end, " \t\r");
            if (!copy_word(m->input_names[i], end, len, line, "inputs (names)", err, err_size))
                return 0;
            end += len;
        }
        break;
    }
    case 4: {
        char *end;
        long h = strtol(rest, &end, 10);
        if (end == rest || h < 1 || h > DEM_MLP_MAX_HIDDEN) {
            dem_mlp_set_error(err, err_size, "line %d (hidden): size must be 1..%d", line, DEM_MLP_MAX_HIDDEN);
            return 0;
        }
        m->nhid = (int)h;
        m->w1 = dem_calloc((size_t)m->nhid * (size_t)m->nin, sizeof(double));
        m->b1 = dem_calloc((size_t)m->nhid, sizeof(double));
        m->w2 = dem_calloc((size_t)m->nhid, sizeof(double));
        if (!m->w1 || !m->b1 || !m->w2) {
            dem_mlp_set_error(err, err_size, "out of memory for %d hidden units", m->nhid);
            return -1;
        }
        break;
    }
    case 5: if (!read_numbers(rest, m->in_lo, m->nin, line, "input_lo", err, err_size)) return 0; break;
    case 6: if (!read_numbers(rest, m->in_hi, m->nin, line, "input_hi", err, err_size)) return 0; break;
    case 7: if (!read_numbers(rest, &m->out_lo, 1, line, "output_lo", err, err_size)) return 0; break;
    case 8: if (!read_numbers(rest, &m->out_hi, 1, line, "output_hi", err, err_size)) return 0; break;
    case 9: if (!read_numbers(rest, m->w1, m->nhid * m->nin, line, "w1", err, err_size)) return 0; break;
    case 10: if (!read_numbers(rest, m->b1, m->nhid, line, "b1", err, err_size)) return 0; break;
    case 11: if (!read_numbers(rest, m->w2, m->nhid, line, "w2", err, err_size)) return 0; break;
    case 12: if (!read_numbers(rest, &m->b2, 1, line, "b2", err, err_size)) return 0; break;
    default: {
        size_t len = strcspn(rest, " \t\r");
        if (len == 8 && strncmp(rest, "identity", 8) == 0)
            m->out_log = 0;
        else if (len == 3 && strncmp(rest, "log", 3) == 0)
            m->out_log = 1;
        else {
            dem_mlp_set_error(err, err_size, "line %d (output_transform): 'identity' or 'log', not '%.*s'", line,
                              (int)len, rest);
            return 0;
        }
        break;
    }
    }
    return 1 << f;
}

dem_status dem_mlp_parse(const char *text, dem_mlp **out, char *err, size_t err_size)
{
    dem_mlp *m;
    int seen = 0, line = 0, i;
    const char *p = text;
    char buf[1 << 16];
    if (!text || !out) {
        dem_mlp_set_error(err, err_size, "dem_mlp_parse: NULL argument");
        return DEM_ERR_NULL;
    }
    *out = NULL;
    m = dem_calloc(1, sizeof *m);
    if (!m)
        return DEM_ERR_NO_MEMORY;
    dem_live_objects(+1); /* dem_mlp_free counts it down */
    while (*p) {
        size_t len = strcspn(p, "\n"), klen;
        char *rest, *dyn = NULL, *s;
        int bit;
        ++line;
        /* long lines (big nets) go to the heap */
        if (len >= sizeof buf) {
            dyn = dem_malloc(len + 1);
            if (!dyn) {
                dem_mlp_free(m);
                return DEM_ERR_NO_MEMORY;
            }
        }
        s = dyn ? dyn : buf;
        memcpy(s, p, len);
        s[len] = '\0';
        p += len + (p[len] == '\n');
        while (*s == ' ' || *s == '\t')
            ++s;
        klen = strcspn(s, " \t\r");
        if (klen == 0 || s[0] == '#') {
            dem_free(dyn);
            continue;
        }
        rest = s + klen;
        while (*rest == ' ' || *rest == '\t')
            ++rest;
        bit = parse_line(m, s, klen, rest, seen, line, err, err_size);
        dem_free(dyn);
        if (bit <= 0) {
            dem_mlp_free(m);
            return bit < 0 ? DEM_ERR_NO_MEMORY : DEM_ERR_FORMAT;
        }
        seen |= bit;
    }
    if ((seen & F_ALL) != F_ALL) {
        int f;
        for (f = 0; f < 13 && (seen & (1 << f)); ++f) {
        }
        dem_mlp_set_error(err, err_size, "keyword '%s' is missing", field_names[f]);
        dem_mlp_free(m);
        return DEM_ERR_FORMAT;
    }
    for (i = 0; i < m->nin; ++i)
        if (!(m->in_hi[i] > m->in_lo[i])) {
            dem_mlp_set_error(err, err_size, "input %d (%s): input_hi must exceed input_lo", i + 1, m->input_names[i]);
            dem_mlp_free(m);
            return DEM_ERR_FORMAT;
        }
    if (!(m->out_hi > m->out_lo)) {
        dem_mlp_set_error(err, err_size, "output_hi must exceed output_lo");
        dem_mlp_free(m);
        return DEM_ERR_FORMAT;
    }
    *out = m;
    return DEM_OK;
}

dem_status dem_mlp_load(const char *path, dem_mlp **out, char *err, size_t err_size)
{
    FILE *fp;
    long size;
    char *text;
    dem_status st;
    if (!path || !out) {
        dem_mlp_set_error(err, err_size, "dem_mlp_load: NULL argument");
        return DEM_ERR_NULL;
    }
    *out = NULL;
    fp = fopen(path, "rb");
    if (!fp) {
        dem_mlp_set_error(err, err_size, "%s: cannot open (%s)", path, strerror(errno));
        return DEM_ERR_IO;
    }
    if (fseek(fp, 0, SEEK_END) != 0 || (size = ftell(fp)) < 0 || fseek(fp, 0, SEEK_SET) != 0) {
        dem_mlp_set_error(err, err_size, "%s: cannot read", path);
        fclose(fp);
        return DEM_ERR_IO;
    }
    text = dem_malloc((size_t)size + 1);
    if (!text) {
        fclose(fp);
        return DEM_ERR_NO_MEMORY;
    }
    if (fread(text, 1, (size_t)size, fp) != (size_t)size) {
        dem_mlp_set_error(err, err_size, "%s: read error", path);
        dem_free(text);
        fclose(fp);
        return DEM_ERR_IO;
    }
    fclose(fp);
    text[size] = '\0';
    if (strlen(text) != (size_t)size) {
        dem_mlp_set_error(err, err_size, "%s: binary data (NUL byte) in a text weights file", path);
        dem_free(text);
        return DEM_ERR_FORMAT;
    }
    st = dem_mlp_parse(text, out, err, err_size);
    dem_free(text);
    if (st == DEM_ERR_FORMAT && err && err_size) { /* prefix the file name */
        char tmp[512];
        snprintf(tmp, sizeof tmp, "%s: %s", path, err);
        dem_mlp_set_error(err, err_size, "%s", tmp);
    }
    return st;
}

static void write_values(FILE *fp, const char *key, const double *v, int n)
{
    int i;
    fputs(key, fp);
    for (i = 0; i < n; ++i)
        fprintf(fp, " %a", v[i]);
    fputc('\n', fp);
}

dem_status dem_mlp_save(const dem_mlp *m, const char *path, char *err, size_t err_size)
{
    FILE *fp;
    int i;
    if (!m || !path) {
        dem_mlp_set_error(err, err_size, "dem_mlp_save: NULL argument");
        return DEM_ERR_NULL;
    }
    fp = fopen(path, "w");
    if (!fp) {
        dem_mlp_set_error(err, err_size, "%s: cannot write (%s)", path, strerror(errno));
        return DEM_ERR_IO;
    }
    fprintf(fp, "dem-mlp 1\nname %s\nunit %s\ninputs %d", m->name, m->unit[0] ? m->unit : "-", m->nin);
    for (i = 0; i < m->nin; ++i)
        fprintf(fp, " %s", m->input_names[i]);
    fprintf(fp, "\nhidden %d\n", m->nhid);
    write_values(fp, "input_lo", m->in_lo, m->nin);
    write_values(fp, "input_hi", m->in_hi, m->nin);
    write_values(fp, "output_lo", &m->out_lo, 1);
    write_values(fp, "output_hi", &m->out_hi, 1);
    write_values(fp, "w1", m->w1, m->nhid * m->nin);
    write_values(fp, "b1", m->b1, m->nhid);
    write_values(fp, "w2", m->w2, m->nhid);
    write_values(fp, "b2", &m->b2, 1);
    if (m->out_log)
        fprintf(fp, "output_transform log\n");
    if (fclose(fp) != 0) {
        dem_mlp_set_error(err, err_size, "%s: write error", path);
        return DEM_ERR_IO;
    }
    return DEM_OK;
}

const char *dem_mlp_name(const dem_mlp *m) { return m ? m->name : NULL; }
const char *dem_mlp_unit(const dem_mlp *m) { return m ? m->unit : NULL; }
int dem_mlp_num_inputs(const dem_mlp *m) { return m ? m->nin : 0; }
int dem_mlp_num_hidden(const dem_mlp *m) { return m ? m->nhid : 0; }
const char *dem_mlp_input_name(const dem_mlp *m, int i) { return m && i >= 0 && i < m->nin ? m->input_names[i] : NULL; }

double dem_mlp_eval(const dem_mlp *m, const double *x)
{
    double xs[DEM_MLP_MAX_INPUTS], y;
    int i, j;
    if (!m || !x)
        return NAN;
    for (i = 0; i < m->nin; ++i)
        xs[i] = (x[i] - m->in_lo[i]) * (2.0 / (m->in_hi[i] - m->in_lo[i])) - 1.0;
    y = m->b2;
    for (j = 0; j < m->nhid; ++j) {
        double z = m->b1[j];
        for (i = 0; i < m->nin; ++i)
            z += m->w1[j * m->nin + i] * xs[i];
        y += m->w2[j] * tanh(z);
    }
    y = (y + 1.0) * ((m->out_hi - m->out_lo) / 2.0) + m->out_lo;
    return m->out_log ? exp(y) : y;
}
