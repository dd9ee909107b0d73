/*
 * ply.c — the PLY (Stanford polygon file) reader: polygon meshes in ascii,
 * binary_little_endian and binary_big_endian, version 1.0.
 *
 * Input is held whole in memory; files larger than 2 GiB are refused before
 * reading. The header is read line by line (LF or CRLF), words separated by
 * spaces or tabs:
 *   header := 'ply'
 *             'format' ('ascii' | 'binary_little_endian' | 'binary_big_endian') '1.0'
 *             ( 'comment' ... | 'obj_info' ... | empty line
 *             | 'element' NAME COUNT
 *             | 'property' TYPE NAME
 *             | 'property' 'list' COUNT_TYPE ITEM_TYPE NAME )*
 *             'end_header'
 *   TYPE := char uchar short ushort int uint float double, or int8 uint8
 *           int16 uint16 int32 uint32 float32 float64
 * Element 'vertex' needs scalar properties x, y and z (any type; float or
 * double in practice); element 'face' needs a list 'vertex_indices' (or
 * 'vertex_index') with integer count and item types. Every other property,
 * list or element is skipped (its values are still checked to be there, and
 * in ascii to be numbers). A file without a 'face' element loads as an empty
 * mesh with a warning. The data follows the header's newline: in ascii as
 * whitespace-separated tokens (coordinates as in NFF: no hex, nan or inf;
 * counts and indices as integers), in binary as packed values of the
 * declared types and byte order. Each face (3 or more vertices, indices from
 * 0) becomes one polygon, in file order.
 *
 * Errors: each failure returns a status and a message naming the file and
 * where: "NAME:LINE: ..." for the header and for ascii data (LINE of the
 * offending token, or of the end of input when data is missing), "NAME: byte
 * OFFSET: ..." for binary data (the offset in the file of the value that is
 * bad or missing). Malformed text, truncated data, bad counts and indices out
 * of range are BSP_ERR_PARSE; non-finite coordinates BSP_ERR_INVALID; absurd
 * sizes BSP_ERR_LIMIT. Element counts are checked against the bytes that
 * follow the header (each binary item takes at least its fixed-size
 * properties and list counts, each ascii value at least two bytes) before
 * anything is allocated. Degenerate faces are dropped by the builder with one
 * warning. On failure *out is NULL and nothing is kept.
 */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/mesh.h"
#include "scene/scene_internal.h"

/* Header limits. */
#define PLY_MAX_ELEMENTS 1024
#define PLY_MAX_PROPERTIES 8192 /* in all elements */
/* The least decimal value that rounds to an infinite float: 2^128 - 2^103 */
#define PLY_FLOAT_ROUNDS_TO_INF 0x1.ffffffp+127

typedef enum ply_type {
    PT_NONE = 0,
    PT_INT8,
    PT_UINT8,
    PT_INT16,
    PT_UINT16,
    PT_INT32,
    PT_UINT32,
    PT_FLOAT32,
    PT_FLOAT64
} ply_type;

static const struct {
    const char *name, *alias;
    size_t size;
} type_info[] = {
    {"", "", 0},
    {"char", "int8", 1},
    {"uchar", "uint8", 1},
    {"short", "int16", 2},
    {"ushort", "uint16", 2},
    {"int", "int32", 4},
    {"uint", "uint32", 4},
    {"float", "float32", 4},
    {"double", "float64", 8},
};

static int type_is_integer(ply_type t)
{
    return t >= PT_INT8 && t <= PT_UINT32;
}

/* The range of integer type T. */
static void integer_range(ply_type t, long long *lo, long long *hi)
{
    int bits = (int)type_info[t].size * 8;
    int is_signed = t == PT_INT8 || t == PT_INT16 || t == PT_INT32;
    *lo = is_signed ? -(1LL << (bits - 1)) : 0;
    *hi = is_signed ? (1LL << (bits - 1)) - 1 : (1LL << bits) - 1;
}

typedef enum ply_role { ROLE_SKIP = 0, ROLE_X, ROLE_Y, ROLE_Z, ROLE_INDICES } ply_role;

typedef enum ply_format { FMT_NONE = 0, FMT_ASCII, FMT_LE, FMT_BE } ply_format;

typedef enum elem_kind { ELEM_OTHER = 0, ELEM_VERTEX, ELEM_FACE } elem_kind;

typedef struct ply_prop {
    const char *name;
    size_t name_len;
    ply_type type;       /* scalar type, or the item type of a list */
    ply_type count_type; /* PT_NONE for a scalar */
    ply_role role;
    size_t line;
} ply_prop;

typedef struct ply_elem {
    const char *name;
    size_t name_len;
    unsigned long long count; /* saturated at 10^18 */
    const char *count_text;   /* the count as written, for messages */
    size_t count_len;
    size_t first, nprops; /* its properties: props[first .. first + nprops) */
    size_t line;
    elem_kind kind;
} ply_elem;

typedef struct ply_parser {
    const char *name;
    const char *buf;
    size_t len;
    size_t pos;  /* data: next byte */
    size_t line; /* ascii data: line at pos */
    size_t tok_line; /* ascii data: line of the last token read */
    bsp_error *err;
    ply_format fmt;
    ply_elem *elems;
    size_t nelems, cap_elems;
    ply_prop *props;
    size_t nprops, cap_props;
    size_t data_start, end_header_line;
    ply_elem *vertex, *face;
    /* the mesh */
    bsp_vec3 *verts;
    uint32_t *idx;
    size_t nidx, cap_idx;
    size_t *face_start; /* face f: idx[face_start[f] .. face_start[f + 1]) */
} ply_parser;

/* --- errors ---------------------------------------------------------------- */

static void vfail_record(ply_parser *P, bsp_status status, int binary_offset, size_t where,
                         const char *fmt, va_list ap)
{
    char msg[BSP_ERROR_MESSAGE_SIZE];
    vsnprintf(msg, sizeof msg, fmt, ap);
    if (binary_offset)
        error_record(P->err, status, P->name, 0, "byte %zu: %s", where, msg);
    else
        error_record(P->err, status, P->name, where, "%s", msg);
}

/* A header error on LINE; yields STATUS (see FAIL_WITH). */
static void hfail_record(ply_parser *P, bsp_status status, size_t line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
#define hfail(P, status, line, ...)                                                            \
    FAIL_WITH(status, hfail_record((P), (status), (line), __VA_ARGS__))

static void hfail_record(ply_parser *P, bsp_status status, size_t line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail_record(P, status, 0, line, fmt, ap);
    va_end(ap);
}

/* A data error at byte offset OFF (binary) or on line LINE (ascii); yields
 * STATUS. */
static void dfail_record(ply_parser *P, bsp_status status, size_t off, size_t line,
                         const char *fmt, ...) __attribute__((format(printf, 5, 6)));
#define dfail(P, status, off, line, ...)                                                       \
    FAIL_WITH(status, dfail_record((P), (status), (off), (line), __VA_ARGS__))

static void dfail_record(ply_parser *P, bsp_status status, size_t off, size_t line,
                         const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int binary = P->fmt != FMT_ASCII;
    vfail_record(P, status, binary, binary ? off : line, fmt, ap);
    va_end(ap);
}

#define SHOW(s, len, buf) mesh_show_token((s), (len), (buf), sizeof(buf))

/* --- the header -------------------------------------------------------------- */

#define MAX_WORDS 8

typedef struct words {
    const char *w[MAX_WORDS];
    size_t len[MAX_WORDS];
    size_t n; /* how many (at most MAX_WORDS are kept) */
} words;

static void split_words(const char *s, const char *e, words *W)
{
    W->n = 0;
    while (s < e) {
        while (s < e && (*s == ' ' || *s == '\t'))
            s++;
        if (s == e)
            break;
        const char *b = s;
        while (s < e && *s != ' ' && *s != '\t')
            s++;
        if (W->n < MAX_WORDS) {
            W->w[W->n] = b;
            W->len[W->n] = (size_t)(s - b);
        }
        W->n++;
    }
}

static int word_eq(const words *W, size_t i, const char *str)
{
    size_t n = strlen(str);
    return i < W->n && i < MAX_WORDS && W->len[i] == n && memcmp(W->w[i], str, n) == 0;
}

static ply_type parse_type(const char *s, size_t len)
{
    for (int t = PT_INT8; t <= PT_FLOAT64; t++) {
        const char *a = type_info[t].name, *b = type_info[t].alias;
        if ((strlen(a) == len && memcmp(a, s, len) == 0) ||
            (strlen(b) == len && memcmp(b, s, len) == 0))
            return (ply_type)t;
    }
    return PT_NONE;
}

static int name_eq(const char *s, size_t len, const char *str)
{
    return strlen(str) == len && memcmp(s, str, len) == 0;
}

/* 'property ...' (words W) on LINE. */
static bsp_status header_property(ply_parser *P, const words *W, size_t line)
{
    char shown[MESH_SHOW_SIZE], shown2[MESH_SHOW_SIZE];
    if (P->nelems == 0)
        return hfail(P, BSP_ERR_PARSE, line, "'property' before any 'element'");
    ply_elem *e = &P->elems[P->nelems - 1];
    int list = word_eq(W, 1, "list");
    size_t need = list ? 5 : 3;
    if (W->n != need)
        return hfail(P, BSP_ERR_PARSE, line,
                     "malformed 'property' line: expected 'property TYPE NAME' or 'property list "
                     "COUNT_TYPE ITEM_TYPE NAME'");
    if (P->nprops >= PLY_MAX_PROPERTIES)
        return hfail(P, BSP_ERR_LIMIT, line, "more than %d properties", PLY_MAX_PROPERTIES);
    if (P->nprops == P->cap_props) {
        size_t ncap = P->cap_props ? 2 * P->cap_props : 16;
        ply_prop *np = realloc(P->props, ncap * sizeof *np);
        if (!np)
            return hfail(P, BSP_ERR_NOMEM, line, "out of memory");
        P->props = np;
        P->cap_props = ncap;
    }
    ply_prop p;
    memset(&p, 0, sizeof p);
    p.line = line;
    p.name = W->w[need - 1];
    p.name_len = W->len[need - 1];
    size_t ti = list ? 3 : 1;
    p.type = parse_type(W->w[ti], W->len[ti]);
    if (p.type == PT_NONE)
        return hfail(P, BSP_ERR_PARSE, line, "unknown property type %s",
                     SHOW(W->w[ti], W->len[ti], shown));
    if (list) {
        p.count_type = parse_type(W->w[2], W->len[2]);
        if (p.count_type == PT_NONE)
            return hfail(P, BSP_ERR_PARSE, line, "unknown property type %s",
                         SHOW(W->w[2], W->len[2], shown));
        if (!type_is_integer(p.count_type))
            return hfail(P, BSP_ERR_PARSE, line,
                         "list %s has count type '%s': it must be an integer type",
                         SHOW(p.name, p.name_len, shown), type_info[p.count_type].name);
    }
    for (size_t i = e->first; i < e->first + e->nprops; i++)
        if (P->props[i].name_len == p.name_len && memcmp(P->props[i].name, p.name, p.name_len) == 0)
            return hfail(P, BSP_ERR_PARSE, line, "duplicate property %s in element %s",
                         SHOW(p.name, p.name_len, shown), SHOW(e->name, e->name_len, shown2));
    if (e->kind == ELEM_VERTEX) {
        static const char *const xyz[3] = {"x", "y", "z"};
        for (int k = 0; k < 3; k++)
            if (name_eq(p.name, p.name_len, xyz[k])) {
                if (list)
                    return hfail(P, BSP_ERR_PARSE, line,
                                 "property '%s' of element 'vertex' is a list", xyz[k]);
                p.role = (ply_role)(ROLE_X + k);
            }
    } else if (e->kind == ELEM_FACE &&
               (name_eq(p.name, p.name_len, "vertex_indices") ||
                name_eq(p.name, p.name_len, "vertex_index"))) {
        if (!list)
            return hfail(P, BSP_ERR_PARSE, line,
                         "property %s of element 'face' is not a list",
                         SHOW(p.name, p.name_len, shown));
        if (!type_is_integer(p.type))
            return hfail(P, BSP_ERR_PARSE, line,
                         "list %s has item type '%s': vertex indices must be of an integer type",
                         SHOW(p.name, p.name_len, shown), type_info[p.type].name);
        for (size_t i = e->first; i < e->first + e->nprops; i++)
            if (P->props[i].role == ROLE_INDICES)
                return hfail(P, BSP_ERR_PARSE, line,
                             "element 'face' has two vertex index lists (%s and %s)",
                             SHOW(P->props[i].name, P->props[i].name_len, shown2),
                             SHOW(p.name, p.name_len, shown));
        p.role = ROLE_INDICES;
    }
    P->props[P->nprops++] = p;
    e->nprops++;
    return BSP_OK;
}

/* 'element NAME COUNT' (words W) on LINE. */
static bsp_status header_element(ply_parser *P, const words *W, size_t line)
{
    char shown[MESH_SHOW_SIZE];
    if (W->n != 3)
        return hfail(P, BSP_ERR_PARSE, line, "malformed 'element' line: expected 'element NAME COUNT'");
    if (P->nelems >= PLY_MAX_ELEMENTS)
        return hfail(P, BSP_ERR_LIMIT, line, "more than %d elements", PLY_MAX_ELEMENTS);
    if (P->nelems == P->cap_elems) {
        size_t ncap = P->cap_elems ? 2 * P->cap_elems : 8;
        ply_elem *ne = realloc(P->elems, ncap * sizeof *ne);
        if (!ne)
            return hfail(P, BSP_ERR_NOMEM, line, "out of memory");
        P->elems = ne;
        P->cap_elems = ncap;
    }
    ply_elem e;
    memset(&e, 0, sizeof e);
    e.name = W->w[1];
    e.name_len = W->len[1];
    e.line = line;
    e.first = P->nprops;
    long long count;
    if (!mesh_parse_integer(W->w[2], W->len[2], &count) || W->w[2][0] == '-' ||
        W->w[2][0] == '+')
        return hfail(P, BSP_ERR_PARSE, line, "element count must be a whole number, found %s",
                     SHOW(W->w[2], W->len[2], shown));
    e.count = (unsigned long long)count;
    e.count_text = W->w[2];
    e.count_len = W->len[2];
    for (size_t i = 0; i < P->nelems; i++)
        if (P->elems[i].name_len == e.name_len && memcmp(P->elems[i].name, e.name, e.name_len) == 0)
            return hfail(P, BSP_ERR_PARSE, line, "second element %s (the first is on line %zu)",
                         SHOW(e.name, e.name_len, shown), P->elems[i].line);
    if (name_eq(e.name, e.name_len, "vertex")) {
        e.kind = ELEM_VERTEX;
        if (e.count > MESH_MAX_VERTS)
            return hfail(P, BSP_ERR_LIMIT, line, "element 'vertex' with %.*s items (the limit is %zu)",
                         (int)e.count_len, e.count_text, MESH_MAX_VERTS);
    } else if (name_eq(e.name, e.name_len, "face")) {
        e.kind = ELEM_FACE;
        if (e.count > SCENE_MAX_PRIMS)
            return hfail(P, BSP_ERR_LIMIT, line, "element 'face' with %.*s items (the limit is %zu)",
                         (int)e.count_len, e.count_text, SCENE_MAX_PRIMS);
    }
    P->elems[P->nelems++] = e;
    return BSP_OK;
}

/* Checks that the declared elements can fit in the bytes after the header. */
static bsp_status check_sizes(ply_parser *P)
{
    const int ascii = P->fmt == FMT_ASCII;
    /* ascii: every value takes a character and a separator, except that the
     * last one in the file needs no separator */
    unsigned long long budget = (unsigned long long)(P->len - P->data_start) + (ascii ? 1 : 0);
    for (size_t i = 0; i < P->nelems; i++) {
        const ply_elem *e = &P->elems[i];
        unsigned long long per = 0;
        for (size_t k = e->first; k < e->first + e->nprops; k++) {
            const ply_prop *p = &P->props[k];
            if (ascii)
                per += 2;
            else
                per += type_info[p->count_type != PT_NONE ? p->count_type : p->type].size;
        }
        if (per == 0 || e->count == 0)
            continue;
        char shown[MESH_SHOW_SIZE];
        unsigned long long remain = ascii ? (budget ? budget - 1 : 0) : budget;
        if (e->count > budget / per)
            return hfail(P, BSP_ERR_PARSE, e->line,
                         "element %s declares %.*s items of at least %llu bytes each, but only "
                         "%llu bytes of data remain (truncated file or bad count)",
                         SHOW(e->name, e->name_len, shown), (int)e->count_len, e->count_text, per,
                         remain);
        budget -= e->count * per;
    }
    return BSP_OK;
}

static bsp_status parse_header(ply_parser *P)
{
    char shown[MESH_SHOW_SIZE];
    size_t pos = 0, line = 0;
    words W;
    for (;;) {
        if (pos >= P->len) {
            if (line == 0)
                return hfail(P, BSP_ERR_PARSE, 1, "not a PLY file: the file is empty");
            return hfail(P, BSP_ERR_PARSE, line, "truncated header: no 'end_header' line");
        }
        line++;
        const char *s = P->buf + pos, *e;
        const char *nl = memchr(s, '\n', P->len - pos);
        e = nl ? nl : P->buf + P->len;
        pos = nl ? (size_t)(nl - P->buf) + 1 : P->len;
        if (e > s && e[-1] == '\r')
            e--;
        split_words(s, e, &W);
        if (line == 1) {
            if (W.n != 1 || !word_eq(&W, 0, "ply") || s[0] != 'p')
                return hfail(P, BSP_ERR_PARSE, 1, "not a PLY file: the first line is %s, not 'ply'",
                             SHOW(s, (size_t)(e - s), shown));
            continue;
        }
        if (W.n == 0 || word_eq(&W, 0, "comment") || word_eq(&W, 0, "obj_info"))
            continue;
        if (word_eq(&W, 0, "format")) {
            if (P->fmt != FMT_NONE)
                return hfail(P, BSP_ERR_PARSE, line, "second 'format' line");
            if (W.n != 3)
                return hfail(P, BSP_ERR_PARSE, line,
                             "malformed 'format' line: expected 'format FORMAT 1.0'");
            if (word_eq(&W, 1, "ascii"))
                P->fmt = FMT_ASCII;
            else if (word_eq(&W, 1, "binary_little_endian"))
                P->fmt = FMT_LE;
            else if (word_eq(&W, 1, "binary_big_endian"))
                P->fmt = FMT_BE;
            else
                return hfail(P, BSP_ERR_PARSE, line,
                             "unsupported format %s (ascii, binary_little_endian or "
                             "binary_big_endian)",
                             SHOW(W.w[1], W.len[1], shown));
            if (!word_eq(&W, 2, "1.0"))
                return hfail(P, BSP_ERR_PARSE, line, "unsupported PLY version %s (only 1.0)",
                             SHOW(W.w[2], W.len[2], shown));
            continue;
        }
        bsp_status st;
        if (word_eq(&W, 0, "element")) {
            if ((st = header_element(P, &W, line)) != BSP_OK)
                return st;
            continue;
        }
        if (word_eq(&W, 0, "property")) {
            if ((st = header_property(P, &W, line)) != BSP_OK)
                return st;
            continue;
        }
        if (word_eq(&W, 0, "end_header")) {
            if (W.n != 1)
                return hfail(P, BSP_ERR_PARSE, line, "malformed 'end_header' line");
            P->end_header_line = line;
            P->data_start = pos;
            break;
        }
        return hfail(P, BSP_ERR_PARSE, line, "unknown header line %s",
                     SHOW(s, (size_t)(e - s), shown));
    }
    if (P->fmt == FMT_NONE)
        return hfail(P, BSP_ERR_PARSE, P->end_header_line, "no 'format' line before 'end_header'");
    for (size_t i = 0; i < P->nelems; i++) {
        ply_elem *e = &P->elems[i];
        if (e->kind == ELEM_VERTEX)
            P->vertex = e;
        else if (e->kind == ELEM_FACE)
            P->face = e;
    }
    if (P->vertex) {
        static const char *const xyz[3] = {"x", "y", "z"};
        for (int k = 0; k < 3; k++) {
            int found = 0;
            for (size_t i = P->vertex->first; i < P->vertex->first + P->vertex->nprops; i++)
                found |= P->props[i].role == (ply_role)(ROLE_X + k);
            if (!found)
                return hfail(P, BSP_ERR_PARSE, P->vertex->line,
                             "element 'vertex' has no property '%s'", xyz[k]);
        }
    }
    if (P->face) {
        int found = 0;
        for (size_t i = P->face->first; i < P->face->first + P->face->nprops; i++)
            found |= P->props[i].role == ROLE_INDICES;
        if (!found)
            return hfail(P, BSP_ERR_PARSE, P->face->line,
                         "element 'face' has no list 'vertex_indices' (or 'vertex_index')");
        if (!P->vertex)
            return hfail(P, BSP_ERR_PARSE, P->face->line,
                         "element 'face' but no element 'vertex'");
    }
    return check_sizes(P);
}

/* --- data ---------------------------------------------------------------------- */

/* The binary value of type T at P in byte order BIG. */
static double get_binary(const unsigned char *p, ply_type t, int big)
{
    size_t n = type_info[t].size;
    uint64_t u = 0;
    if (big)
        for (size_t i = 0; i < n; i++)
            u = u << 8 | p[i];
    else
        for (size_t i = n; i-- > 0;)
            u = u << 8 | p[i];
    switch (t) {
    case PT_INT8:
        return (double)((long long)u - (u & 0x80u ? 0x100 : 0));
    case PT_UINT8:
    case PT_UINT16:
    case PT_UINT32:
        return (double)u;
    case PT_INT16:
        return (double)((long long)u - (u & 0x8000u ? 0x10000 : 0));
    case PT_INT32:
        return (double)((long long)u - (u & 0x80000000u ? 0x100000000LL : 0));
    case PT_FLOAT32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, sizeof f);
        return (double)f;
    }
    case PT_FLOAT64: {
        double d;
        memcpy(&d, &u, sizeof d);
        return d;
    }
    case PT_NONE:
        break;
    }
    return 0.0;
}

/* The next ascii token (0 at the end of input). */
static int ascii_token(ply_parser *P, const char **s, size_t *len, size_t *line)
{
    const char *b = P->buf, *p = b + P->pos, *end = b + P->len;
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n' || *p == '\v' ||
                       *p == '\f')) {
        if (*p == '\n')
            P->line++;
        p++;
    }
    if (p == end) {
        P->pos = P->len;
        *line = P->tok_line; /* data missing: blame the last line that had some */
        return 0;
    }
    *line = P->tok_line = P->line;
    const char *t = p;
    while (p < end && !(*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n' || *p == '\v' ||
                        *p == '\f'))
        p++;
    *s = t;
    *len = (size_t)(p - t);
    P->pos = (size_t)(p - b);
    return 1;
}

/* "vertex 3" or "element 'edge' item 3", for messages. */
static const char *item_name(const ply_elem *e, unsigned long long item, char *buf, size_t size)
{
    char shown[MESH_SHOW_SIZE];
    if (e->kind == ELEM_VERTEX)
        snprintf(buf, size, "vertex %llu", item);
    else if (e->kind == ELEM_FACE)
        snprintf(buf, size, "face %llu", item);
    else
        snprintf(buf, size, "element %s item %llu", SHOW(e->name, e->name_len, shown), item);
    return buf;
}

/* Where a value is: "ITEM, property 'NAME'". */
typedef struct where {
    const ply_elem *e;
    unsigned long long item;
    const ply_prop *p;
} where;

static const char *where_str(const where *w, char *buf, size_t size)
{
    char item[160], shown[MESH_SHOW_SIZE];
    snprintf(buf, size, "%s, property %s", item_name(w->e, w->item, item, sizeof item),
             SHOW(w->p->name, w->p->name_len, shown));
    return buf;
}

/* Reads one value of type T: as a double in *D (INTEGER: an integer in *I). */
static bsp_status read_value(ply_parser *P, const where *w, ply_type t, int integer,
                             int must_be_finite, double *d, long long *i)
{
    char at[256], shown[MESH_SHOW_SIZE];
    if (P->fmt != FMT_ASCII) {
        size_t n = type_info[t].size;
        if (P->len - P->pos < n)
            return dfail(P, BSP_ERR_PARSE, P->pos, 0,
                         "truncated data: %s needs %zu bytes, %zu remain",
                         where_str(w, at, sizeof at), n, P->len - P->pos);
        double v = get_binary((const unsigned char *)P->buf + P->pos, t, P->fmt == FMT_BE);
        if (must_be_finite && !isfinite(v))
            return dfail(P, BSP_ERR_INVALID, P->pos, 0, "non-finite number (%g) in %s", v,
                         where_str(w, at, sizeof at));
        if (must_be_finite && fabs(v) > BSP_SCENE_MAX_COORD)
            return dfail(P, BSP_ERR_INVALID, P->pos, 0,
                         "%g in %s is out of range (coordinates "
                         "must lie within +-%g)",
                         v, where_str(w, at, sizeof at), BSP_SCENE_MAX_COORD);
        P->pos += n;
        if (integer)
            *i = (long long)v; /* integer types only: exact */
        else
            *d = v;
        return BSP_OK;
    }
    const char *s;
    size_t len, line;
    if (!ascii_token(P, &s, &len, &line))
        return dfail(P, BSP_ERR_PARSE, 0, line, "truncated data: %s is missing (end of input)",
                     where_str(w, at, sizeof at));
    /* An ASCII value must be what its declared type can hold, as in binary
     * files: an integer type takes an integer in its range, float a finite
     * value within float's range (or a non-finite one where allowed). */
    if (type_is_integer(t)) {
        long long k, lo, hi;
        if (!mesh_parse_integer(s, len, &k))
            return dfail(P, BSP_ERR_PARSE, 0, line, "malformed integer %s in %s (type %s)",
                         SHOW(s, len, shown), where_str(w, at, sizeof at), type_info[t].name);
        integer_range(t, &lo, &hi);
        if (k < lo || k > hi)
            return dfail(P, BSP_ERR_PARSE, 0, line,
                         "%s in %s is out of range of type %s (%lld to %lld)", SHOW(s, len, shown),
                         where_str(w, at, sizeof at), type_info[t].name, lo, hi);
        if (integer)
            *i = k;
        else
            *d = (double)k;
        return BSP_OK;
    }
    double v = 0.0;
    mesh_number r = mesh_parse_number(s, len, &v);
    if (r == MESH_NUM_MALFORMED)
        return dfail(P, BSP_ERR_PARSE, 0, line, "malformed number %s in %s", SHOW(s, len, shown),
                     where_str(w, at, sizeof at));
    if (r == MESH_NUM_NONFINITE && must_be_finite)
        return dfail(P, BSP_ERR_INVALID, 0, line, "non-finite number %s in %s",
                     SHOW(s, len, shown), where_str(w, at, sizeof at));
    /* float's range as a decimal reaches it: every value that rounds to a
     * finite float, up to (not including) 2^128 - 2^103, the midpoint between
     * FLT_MAX and 2^128 (FLT_MAX printed with 9 digits, 3.40282347e+38, or
     * as the shortest string that reads back, 3.4028235e+38, lies above
     * FLT_MAX but rounds to it) */
    if (t == PT_FLOAT32 && isfinite(v) && fabs(v) >= PLY_FLOAT_ROUNDS_TO_INF)
        return dfail(P, BSP_ERR_PARSE, 0, line, "%s in %s is out of range of type float",
                     SHOW(s, len, shown), where_str(w, at, sizeof at));
    if (must_be_finite && fabs(v) > BSP_SCENE_MAX_COORD)
        return dfail(P, BSP_ERR_INVALID, 0, line,
                     "%s in %s is out of range (coordinates must lie within +-%g)",
                     SHOW(s, len, shown), where_str(w, at, sizeof at), BSP_SCENE_MAX_COORD);
    *d = v;
    return BSP_OK;
}

/* A list: its count, then its items (indices of a face are kept). */
static bsp_status read_list(ply_parser *P, const where *w)
{
    const ply_prop *p = w->p;
    char at[256];
    size_t off = P->pos, line = 0;
    long long n = 0;
    double dummy;
    bsp_status st = read_value(P, w, p->count_type, 1, 0, &dummy, &n);
    if (st != BSP_OK)
        return st;
    if (P->fmt == FMT_ASCII)
        line = P->tok_line;
    if (n < 0)
        return dfail(P, BSP_ERR_PARSE, off, line, "negative list count %lld in %s", n,
                     where_str(w, at, sizeof at));
    size_t item = P->fmt == FMT_ASCII ? 2 : type_info[p->type].size;
    size_t remain = P->len - P->pos + (P->fmt == FMT_ASCII ? 1 : 0);
    if (p->role == ROLE_INDICES) {
        if (n < 3)
            return dfail(P, BSP_ERR_PARSE, off, line,
                         "face %llu has %lld vertices (at least 3 are needed)", w->item, n);
        if ((unsigned long long)n > SCENE_MAX_POLY_VERTS)
            return dfail(P, BSP_ERR_LIMIT, off, line,
                         "face %llu has %lld vertices (the limit is %zu)", w->item, n,
                         SCENE_MAX_POLY_VERTS);
    }
    if ((unsigned long long)n > remain / item)
        return dfail(P, BSP_ERR_PARSE, off, line,
                     "truncated data: list of %lld items in %s, but only %zu bytes remain", n,
                     where_str(w, at, sizeof at), P->len - P->pos);
    if (p->role != ROLE_INDICES) {
        if (P->fmt != FMT_ASCII) {
            P->pos += (size_t)n * item;
            return BSP_OK;
        }
        for (long long k = 0; k < n; k++)
            if ((st = read_value(P, w, p->type, 0, 0, &dummy, NULL)) != BSP_OK)
                return st;
        return BSP_OK;
    }
    if (P->nidx + (size_t)n > P->cap_idx) {
        size_t ncap = P->cap_idx ? P->cap_idx : 1024;
        while (ncap < P->nidx + (size_t)n)
            ncap *= 2;
        uint32_t *a = realloc(P->idx, ncap * sizeof *a);
        if (!a)
            return dfail(P, BSP_ERR_NOMEM, off, line, "out of memory");
        P->idx = a;
        P->cap_idx = ncap;
    }
    const unsigned long long nv = P->vertex->count;
    for (long long k = 0; k < n; k++) {
        size_t voff = P->pos;
        long long v = 0;
        if ((st = read_value(P, w, p->type, 1, 0, &dummy, &v)) != BSP_OK)
            return st;
        if (v < 0 || (unsigned long long)v >= nv)
            return dfail(P, BSP_ERR_PARSE, voff, P->tok_line,
                         "vertex index %lld in face %llu is out of range (%llu vertices)", v,
                         w->item, nv);
        P->idx[P->nidx++] = (uint32_t)v;
    }
    return BSP_OK;
}

static bsp_status read_data(ply_parser *P)
{
    P->pos = P->data_start;
    P->line = P->end_header_line + 1;
    P->tok_line = P->end_header_line;
    for (size_t i = 0; i < P->nelems; i++) {
        const ply_elem *e = &P->elems[i];
        if (e->nprops == 0)
            continue; /* nothing to read, whatever the count */
        for (unsigned long long item = 0; item < e->count; item++) {
            if (e->kind == ELEM_FACE)
                P->face_start[item] = P->nidx;
            for (size_t k = e->first; k < e->first + e->nprops; k++) {
                const ply_prop *p = &P->props[k];
                where w = {e, item, p};
                bsp_status st;
                if (p->count_type != PT_NONE) {
                    st = read_list(P, &w);
                } else {
                    double v = 0.0;
                    int coord = p->role >= ROLE_X && p->role <= ROLE_Z;
                    st = read_value(P, &w, p->type, 0, coord, &v, NULL);
                    if (st == BSP_OK && coord)
                        P->verts[item].v[p->role - ROLE_X] = v;
                }
                if (st != BSP_OK)
                    return st;
            }
        }
        if (e->kind == ELEM_FACE)
            P->face_start[e->count] = P->nidx;
    }
    if (P->fmt == FMT_ASCII) {
        const char *s;
        size_t len, line;
        char shown[MESH_SHOW_SIZE];
        if (ascii_token(P, &s, &len, &line))
            return dfail(P, BSP_ERR_PARSE, 0, line, "extra data %s after the last element",
                         SHOW(s, len, shown));
    }
    return BSP_OK;
}

/* --- the scene ------------------------------------------------------------------- */

static bsp_status build(ply_parser *P, bsp_scene *scene)
{
    if (!P->face)
        return BSP_OK;
    size_t cap = 0;
    bsp_vec3 *buf = NULL;
    bsp_status st = BSP_OK;
    scene_set_source(scene, P->name, 0);
    for (unsigned long long f = 0; f < P->face->count && st == BSP_OK; f++) {
        size_t a = P->face_start[f], n = P->face_start[f + 1] - a;
        if (n > cap) {
            size_t ncap = cap ? cap : 16;
            while (ncap < n)
                ncap *= 2;
            bsp_vec3 *nb = realloc(buf, ncap * sizeof *nb);
            if (!nb) {
                st = error_set(P->err, BSP_ERR_NOMEM, P->name, 0, "out of memory");
                break;
            }
            buf = nb;
            cap = ncap;
        }
        for (size_t k = 0; k < n; k++)
            buf[k] = P->verts[P->idx[a + k]];
        st = bsp_scene_add_polygon(scene, buf, n, P->err);
    }
    free(buf);
    return st;
}

static bsp_status parse_ply(const char *buf, size_t len, const char *name, bsp_scene **out,
                            bsp_error *err)
{
    ply_parser P;
    memset(&P, 0, sizeof P);
    P.name = name;
    P.buf = buf;
    P.len = len;
    P.err = err;
    bsp_scene *scene = NULL;
    bsp_status st = BSP_OK;
    if ((st = parse_header(&P)) != BSP_OK)
        goto done;
    /* the counts fit in the file (check_sizes): allocation is bounded by it */
    if (P.vertex && P.vertex->count) {
        P.verts = malloc((size_t)P.vertex->count * sizeof *P.verts);
        if (!P.verts) {
            st = error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory");
            goto done;
        }
    }
    if (P.face) {
        P.face_start = malloc(((size_t)P.face->count + 1) * sizeof *P.face_start);
        if (!P.face_start) {
            st = error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory");
            goto done;
        }
    }
    if ((st = read_data(&P)) != BSP_OK)
        goto done;
    scene = mesh_scene_create();
    if (!scene) {
        st = error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory");
        goto done;
    }
    if ((st = build(&P, scene)) != BSP_OK)
        goto done;
    if (!P.face)
        scene_warn(scene, "%s: no element 'face': the mesh has no surfaces", name);
    if (P.fmt != FMT_ASCII && P.pos < P.len)
        scene_warn(scene, "%s: byte %zu: ignored %zu bytes after the last element", name, P.pos,
                   P.len - P.pos);
    st = mesh_finish(scene, name, err);
done:
    free(P.elems);
    free(P.props);
    free(P.verts);
    free(P.idx);
    free(P.face_start);
    if (st != BSP_OK) {
        bsp_scene_destroy(scene);
        return st;
    }
    *out = scene;
    return BSP_OK;
}

/* parse_ply on plain or gzip input. */
static bsp_status parse_ply_any(const char *buf, size_t len, const char *name, bsp_scene **out,
                                bsp_error *err)
{
    return scene_parse_maybe_gzip(parse_ply, buf, len, name, MESH_MAX_INPUT, 0, out, err);
}

bsp_status ply_load_memory(const char *buf, size_t len, const char *name, bsp_scene **out,
                           bsp_error *err)
{
    return mesh_load_memory(parse_ply_any, buf, len, name, out, err);
}

bsp_status ply_load_file(const char *path, bsp_scene **out, bsp_error *err)
{
    return mesh_load_file(parse_ply_any, path, out, err);
}
