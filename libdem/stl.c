/* STL reader: ASCII or binary into a triangle soup (9 doubles per triangle). Binary is
 * recognised by its size (84 + 50 n bytes with n from the header), so binary files whose
 * header starts with "solid" still read; everything else must parse as ASCII. Every failure
 * says what and where (byte offset or line). The parser only ever reads inside the buffer
 * (fuzzed: tests/c/test_stl.c and tests/data/stl_corpus). */
#include "stl.h"
#include "alloc.h"
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint32_t read_u32le(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float read_f32le(const unsigned char *p)
{
    uint32_t u = read_u32le(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static int parse_binary(const unsigned char *buf, size_t len, stl_soup *out, char *err, size_t errsz)
{
    uint32_t n = read_u32le(buf + 80);
    out->xyz = dem_malloc((size_t)(n ? n : 1) * 9 * sizeof(double));
    if (!out->xyz) {
        snprintf(err, errsz, "binary STL: out of memory for %u triangles", n);
        return STL_NO_MEMORY;
    }
    for (uint32_t t = 0; t < n; t++) {
        const unsigned char *rec = buf + 84 + (size_t)t * 50 + 12; /* skip the stored normal */
        for (int k = 0; k < 9; k++) {
            double v = read_f32le(rec + 4 * k);
            if (!isfinite(v)) {
                snprintf(err, errsz, "binary STL: triangle %u has a non-finite coordinate (NaN/inf)", t);
                return STL_BAD;
            }
            out->xyz[9 * (size_t)t + k] = v;
        }
    }
    out->n = n;
    (void)len;
    return STL_OK;
}

/* ASCII tokenizer over a bounded buffer. */
typedef struct cursor {
    const char *p, *end;
    int line;
} cursor;

static void skip_space(cursor *c)
{
    while (c->p < c->end && isspace((unsigned char)*c->p)) {
        if (*c->p == '\n') c->line++;
        c->p++;
    }
}

/* Next whitespace-delimited token into tok (truncated to toksz - 1), in lower case: keywords
 * are case-insensitive ("SOLID", "Facet" are written by some exporters) and numbers read the
 * same; 0 at end of input. */
static int next_token(cursor *c, char *tok, size_t toksz)
{
    skip_space(c);
    if (c->p >= c->end) return 0;
    size_t k = 0;
    while (c->p < c->end && !isspace((unsigned char)*c->p)) {
        if (k + 1 < toksz) tok[k++] = (char)tolower((unsigned char)*c->p);
        c->p++;
    }
    tok[k] = '\0';
    return 1;
}

static void skip_line(cursor *c)
{
    while (c->p < c->end && *c->p != '\n') c->p++;
}

static int expect(cursor *c, const char *word, char *err, size_t errsz)
{
    char tok[64];
    if (!next_token(c, tok, sizeof tok)) {
        snprintf(err, errsz, "ASCII STL: unexpected end of file at line %d, expected '%s'", c->line, word);
        return 0;
    }
    if (strcmp(tok, word) != 0) {
        snprintf(err, errsz, "ASCII STL: line %d: expected '%s', found '%.40s'", c->line, word, tok);
        return 0;
    }
    return 1;
}

static int read_number(cursor *c, double *v, char *err, size_t errsz)
{
    char tok[64];
    if (!next_token(c, tok, sizeof tok)) {
        snprintf(err, errsz, "ASCII STL: unexpected end of file at line %d, expected a number", c->line);
        return 0;
    }
    char *endp;
    errno = 0;
    *v = strtod(tok, &endp);
    if (endp == tok || *endp != '\0') {
        snprintf(err, errsz, "ASCII STL: line %d: '%.40s' is not a number", c->line, tok);
        return 0;
    }
    if (!isfinite(*v)) {
        snprintf(err, errsz, "ASCII STL: line %d: non-finite coordinate '%.40s'", c->line, tok);
        return 0;
    }
    return 1;
}

static int parse_ascii(const unsigned char *buf, size_t len, stl_soup *out, char *err, size_t errsz)
{
    cursor c = {(const char *)buf, (const char *)buf + len, 1};
    size_t cap = 64, n = 0;
    out->xyz = dem_malloc(cap * 9 * sizeof(double));
    if (!out->xyz) {
        snprintf(err, errsz, "ASCII STL: out of memory");
        return STL_NO_MEMORY;
    }
    char tok[64];
    int solids = 0;
    while (next_token(&c, tok, sizeof tok)) {
        if (strcmp(tok, "solid") != 0) {
            snprintf(err, errsz, "ASCII STL: line %d: expected 'solid', found '%.40s'", c.line, tok);
            return STL_BAD;
        }
        solids++;
        skip_line(&c); /* the solid's name */
        for (;;) {
            if (!next_token(&c, tok, sizeof tok)) {
                snprintf(err, errsz, "ASCII STL: unexpected end of file at line %d inside a solid (missing 'endsolid')",
                         c.line);
                return STL_BAD;
            }
            if (strcmp(tok, "endsolid") == 0) {
                skip_line(&c);
                break;
            }
            if (strcmp(tok, "facet") != 0) {
                snprintf(err, errsz, "ASCII STL: line %d: expected 'facet' or 'endsolid', found '%.40s'", c.line, tok);
                return STL_BAD;
            }
            double normal[3];
            if (!expect(&c, "normal", err, errsz)) return STL_BAD;
            for (int k = 0; k < 3; k++)
                if (!read_number(&c, &normal[k], err, errsz)) return STL_BAD;
            if (!expect(&c, "outer", err, errsz) || !expect(&c, "loop", err, errsz)) return STL_BAD;
            if (n == cap) {
                double *p = dem_realloc(out->xyz, 2 * cap * 9 * sizeof(double));
                if (!p) {
                    snprintf(err, errsz, "ASCII STL: out of memory");
                    return STL_NO_MEMORY;
                }
                out->xyz = p;
                cap *= 2;
            }
            for (int v = 0; v < 3; v++) {
                if (!expect(&c, "vertex", err, errsz)) return STL_BAD;
                for (int k = 0; k < 3; k++)
                    if (!read_number(&c, &out->xyz[9 * n + 3 * v + k], err, errsz)) return STL_BAD;
            }
            if (!expect(&c, "endloop", err, errsz) || !expect(&c, "endfacet", err, errsz)) return STL_BAD;
            n++;
        }
    }
    if (solids == 0) {
        snprintf(err, errsz, "ASCII STL: no 'solid' found");
        return STL_BAD;
    }
    out->n = n;
    return STL_OK;
}

/* ASCII STL: after an optional UTF-8 byte-order mark and white space, "solid" in any case, and
 * no NUL byte anywhere. */
static int starts_ascii(const unsigned char *buf, size_t len)
{
    size_t i = (len >= 3 && buf[0] == 0xEF && buf[1] == 0xBB && buf[2] == 0xBF) ? 3 : 0;
    while (i < len && isspace(buf[i])) i++;
    static const char word[] = "solid";
    for (int k = 0; k < 5; k++)
        if (i + (size_t)k >= len || tolower(buf[i + (size_t)k]) != word[k]) return 0;
    return memchr(buf, '\0', len) == NULL;
}

int dem_stl_parse(const unsigned char *buf, size_t len, stl_soup *out, char *err, size_t errsz)
{
    out->xyz = NULL;
    out->n = 0;
    int rc;
    if (len == 0) {
        snprintf(err, errsz, "empty file");
        rc = STL_BAD;
    } else if (len >= 84 && (uint64_t)len == 84 + 50 * (uint64_t)read_u32le(buf + 80)) {
        rc = parse_binary(buf, len, out, err, errsz);
    } else if (starts_ascii(buf, len)) {
        size_t skip = (len >= 3 && buf[0] == 0xEF && buf[1] == 0xBB && buf[2] == 0xBF) ? 3 : 0; /* UTF-8 BOM */
        rc = parse_ascii(buf + skip, len - skip, out, err, errsz);
    } else if (len >= 84) {
        uint32_t n = read_u32le(buf + 80);
        snprintf(err, errsz,
                 "not ASCII STL, and as binary STL the header says %u triangles (%llu bytes) but the file has %llu "
                 "bytes (truncated or corrupt)",
                 n, (unsigned long long)(84 + 50 * (uint64_t)n), (unsigned long long)len);
        rc = STL_BAD;
    } else {
        snprintf(err, errsz, "file of %llu bytes is neither ASCII STL nor a binary STL (at least 84 bytes)",
                 (unsigned long long)len);
        rc = STL_BAD;
    }
    if (rc != STL_OK) {
        dem_free(out->xyz);
        out->xyz = NULL;
        out->n = 0;
    }
    return rc;
}

int dem_stl_read_file(const char *path, stl_soup *out, char *err, size_t errsz)
{
    out->xyz = NULL;
    out->n = 0;
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        snprintf(err, errsz, "cannot open '%s': %s", path, strerror(errno));
        return STL_IO;
    }
    unsigned char *buf = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len == cap) {
            size_t c = cap ? 2 * cap : 1 << 16;
            unsigned char *p = dem_realloc(buf, c);
            if (!p) {
                dem_free(buf);
                fclose(fp);
                snprintf(err, errsz, "'%s': out of memory while reading", path);
                return STL_NO_MEMORY;
            }
            buf = p;
            cap = c;
        }
        size_t got = fread(buf + len, 1, cap - len, fp);
        len += got;
        if (got == 0) break;
    }
    int read_error = ferror(fp);
    fclose(fp);
    if (read_error) {
        dem_free(buf);
        snprintf(err, errsz, "cannot read '%s' (is it a directory?)", path);
        return STL_IO;
    }
    char inner[400];
    int rc = dem_stl_parse(buf, len, out, inner, sizeof inner);
    dem_free(buf);
    if (rc != STL_OK) snprintf(err, errsz, "'%s': %s", path, inner);
    return rc;
}
