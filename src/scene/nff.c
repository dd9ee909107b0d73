/*
 * nff.c — the NFF scene reader: bsp_scene_load and bsp_scene_load_nff_memory.
 *
 * Input is held whole in memory. Files larger than 2 GiB are refused before
 * reading; gzip input (magic bytes 1f 8b, or a name ending in ".gz") is
 * inflated with zlib first, and refused when it inflates beyond 2 GiB.
 * A hand-written tokenizer then scans the buffer: a token is a run of bytes
 * that are neither whitespace nor '#', and '#' starts a comment that runs to
 * the end of the line. Records are read by tokens, never by lines, so a `c`
 * may sit on one line (as SPD writes it) or on three (as NFF.TXT shows it).
 *
 * Grammar accepted (N: a decimal number, I: an integer token [+-]?[0-9]+):
 *   file   := record*
 *   record := 'v' 'from' N N N 'at' N N N 'up' N N N 'angle' N 'hither' N
 *                 'resolution' I I                    -- at most one v block
 *           | 'b' N N N                               -- background
 *           | 'l' N N N [N N N]                       -- light [colour]
 *           | 'f' N N N N N N N N                     -- r g b Kd Ks Shine T ior
 *           | 'c' N N N N N N N N                     -- base xyz r, apex xyz r
 *           | 's' N N N N                             -- centre xyz, radius
 *           | 'p' I (N N N){I}                        -- polygon
 *           | 'pp' I (N N N N N N){I}                 -- vertex and normal
 *   A number is what strtod reads from [+-]? digits [. digits] [(e|E) [+-] digits]
 *   (consuming the whole token); hex, "nan" and "inf" are refused, and so is
 *   a number that overflows to infinity. An `l` has a colour when the token
 *   after its position looks like a number. Entities may come in any order.
 *
 * Errors: each failure returns a status and the message "NAME:LINE: what is
 * wrong", NAME being the path (or the name given with a memory buffer) and
 * LINE the line of the offending token — for a record cut short, and for a
 * value the builder refuses, the line of the record's keyword (of 'v' for the
 * camera vectors). I/O and gzip errors are "NAME: ..." alone. Malformed text is BSP_ERR_PARSE,
 * non-finite numbers and values out of their domain BSP_ERR_INVALID, absurd sizes BSP_ERR_LIMIT.
 * Values are validated by the scene builder (scene.c), which reports with the location set here.
 * Degenerate primitives are not errors: the builder drops them with one warning per kind. On
 * failure *out is NULL and nothing is kept.
 */
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>


#include "scene/mesh.h"
#include "scene/scene_internal.h"

/* Largest input accepted, as read and as inflated. */
#define NFF_MAX_INPUT ((size_t)1 << 31)

/* --- tokens ----------------------------------------------------------------- */

typedef struct token {
    const char *s; /* first byte, NULL at end of input */
    size_t len;    /* bytes */
    size_t line;   /* 1-based line of the first byte */
} token;

typedef enum keyword {
    KW_NONE = 0,
    KW_V,
    KW_B,
    KW_L,
    KW_F,
    KW_C,
    KW_S,
    KW_P,
    KW_PP,
    KW_FROM,
    KW_AT,
    KW_UP,
    KW_ANGLE,
    KW_HITHER,
    KW_RESOLUTION
} keyword;

static const char *const keyword_name[] = {"",   "v",  "b",     "l",      "f",
                                           "c",  "s",  "p",     "pp",     "from",
                                           "at", "up", "angle", "hither", "resolution"};

/* What NFF.TXT says of an 'f' record's numbers, beyond their signs (which
 * the scene refuses): "RGB is in terms of 0.0 to 1.0"; "usually, 0 <= Kd
 * <= 1 and 0 <= Ks <= 1"; T is a "fraction of contribution of the
 * transmitting ray". Larger values are read as given, with a warning: a
 * Whitted ray of depth 4 multiplies by Ks or T up to four times, so values
 * far above 1 make pixels overflow to infinity (T = 3e29: found by fuzzing). */
enum { RANGE_COLOUR, RANGE_KD_KS, RANGE_T, MATERIAL_RANGE_KINDS };

typedef struct parser {
    const char *name; /* for messages */
    const char *p;    /* scan position: just after tok */
    const char *end;
    size_t line; /* line at p */
    token tok;   /* the lookahead token */
    bsp_scene *scene;
    bsp_error *err;
    bsp_vec3 *vbuf; /* reusable vertex (and normal) buffer of polygons */
    size_t vcap;
    size_t v_line; /* line of the v block, 0 before it */
    /* 'f' records outside the ranges NFF.TXT gives, per kind (warned once
     * per kind at the end): how many, and the line and value of the first */
    struct {
        size_t count, line;
        double value;
    } out_of_range[MATERIAL_RANGE_KINDS];
} parser;

static int is_space(char c)
{
    return c == ' ' || c == '\n' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

/* Scans the next token into P->tok (tok.s == NULL at end of input). */
static void lex_advance(parser *P)
{
    const char *p = P->p, *end = P->end;
    size_t line = P->line;
    for (;;) {
        while (p < end && is_space(*p)) {
            if (*p == '\n')
                line++;
            p++;
        }
        if (p < end && *p == '#') {
            const char *nl = memchr(p, '\n', (size_t)(end - p));
            p = nl ? nl : end;
            continue;
        }
        break;
    }
    P->tok.line = line;
    if (p == end) {
        P->tok.s = NULL;
        P->tok.len = 0;
    } else {
        const char *s = p;
        while (p < end && !is_space(*p) && *p != '#')
            p++;
        P->tok.s = s;
        P->tok.len = (size_t)(p - s);
    }
    P->p = p;
    P->line = line;
}

static keyword token_keyword(const token *t)
{
    if (!t->s)
        return KW_NONE;
    const char *s = t->s;
    switch (t->len) { /* called once per record: keep it cheap */
    case 1:
        switch (s[0]) {
        case 'v':
            return KW_V;
        case 'b':
            return KW_B;
        case 'l':
            return KW_L;
        case 'f':
            return KW_F;
        case 'c':
            return KW_C;
        case 's':
            return KW_S;
        case 'p':
            return KW_P;
        }
        return KW_NONE;
    case 2:
        if (s[0] == 'p' && s[1] == 'p')
            return KW_PP;
        if (s[0] == 'a' && s[1] == 't')
            return KW_AT;
        if (s[0] == 'u' && s[1] == 'p')
            return KW_UP;
        return KW_NONE;
    default:
        for (size_t k = KW_FROM; k <= KW_RESOLUTION; k++) {
            const char *n = keyword_name[k];
            if (strlen(n) == t->len && memcmp(n, s, t->len) == 0)
                return (keyword)k;
        }
        return KW_NONE;
    }
}

/* The token quoted for a message, bytes that are not printable escaped and
 * long tokens cut; "end of input" at the end. */
static const char *token_show(const token *t, char *buf, size_t size)
{
    if (!t->s) {
        snprintf(buf, size, "end of input");
        return buf;
    }
    size_t n = 0, limit = size - 8; /* room for the quotes, "..." and NUL */
    buf[n++] = '\'';
    size_t i;
    for (i = 0; i < t->len && n + 4 <= limit; i++) {
        unsigned char c = (unsigned char)t->s[i];
        if (c >= 0x20 && c < 0x7f && c != '\'' && c != '\\') {
            buf[n++] = (char)c;
        } else {
            snprintf(buf + n, size - n, "\\x%02x", c);
            n += 4;
        }
    }
    if (i < t->len) {
        memcpy(buf + n, "...", 3);
        n += 3;
    }
    buf[n++] = '\'';
    buf[n] = '\0';
    return buf;
}

#define SHOW_SIZE 64

/* --- numbers ---------------------------------------------------------------- */

/* Numbers are read by mesh_parse_number (scene/mesh.h), shared with the
 * OBJ and PLY readers: the value strtod gives, bit for bit. */

/* Reads the token as [+-]?[0-9]+ (saturated at +-10^18); 0 if it is not one. */
static int parse_integer(const token *t, long long *out)
{
    return t->s && mesh_parse_integer(t->s, t->len, out);
}

/* True when the token reads as a number, or is trying to be one. */
static int looks_numeric(const token *t)
{
    if (!t->s)
        return 0;
    double v;
    if (mesh_parse_number(t->s, t->len, &v) != MESH_NUM_MALFORMED)
        return 1;
    char c = t->s[0];
    return is_digit(c) || c == '+' || c == '-' || c == '.';
}

/* --- errors ----------------------------------------------------------------- */

static void fail_record(parser *P, bsp_status status, size_t line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* Records a parse error on LINE and yields STATUS (see FAIL_WITH). */
#define fail(P, status, line, ...) FAIL_WITH(status, fail_record((P), (status), (line), __VA_ARGS__))

static void fail_record(parser *P, bsp_status status, size_t line, const char *fmt, ...)
{
    char msg[BSP_ERROR_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    error_record(P->err, status, P->name, line, "%s", msg);
}

/* WHAT (e.g. "'s' record") begun on line REC_LINE ended early at token T. */
static bsp_status truncated(parser *P, const char *what, size_t rec_line, size_t expected,
                            const token *t)
{
    char shown[SHOW_SIZE];
    token_show(t, shown, sizeof shown);
    if (t->s && t->line != rec_line)
        return fail(P, BSP_ERR_PARSE, rec_line,
                    "truncated %s: expected %zu numbers, found %s on line %zu", what, expected,
                    shown, t->line);
    return fail(P, BSP_ERR_PARSE, rec_line, "truncated %s: expected %zu numbers, found %s", what,
                expected, shown);
}

/* Reads N numbers into OUT for WHAT (begun on REC_LINE) that expects
 * EXPECTED numbers in all. */
static bsp_status read_numbers(parser *P, const char *what, size_t rec_line, size_t expected,
                               double *out, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const token t = P->tok;
        if (!t.s)
            return truncated(P, what, rec_line, expected, &t);
        mesh_number r = mesh_parse_number(t.s, t.len, &out[i]);
        if (r != MESH_NUM_OK) {
            char shown[SHOW_SIZE];
            token_show(&t, shown, sizeof shown);
            if (r == MESH_NUM_NONFINITE)
                return fail(P, BSP_ERR_INVALID, t.line, "non-finite number %s in %s", shown, what);
            if (token_keyword(&t) != KW_NONE)
                return truncated(P, what, rec_line, expected, &t);
            return fail(P, BSP_ERR_PARSE, t.line, "malformed number %s in %s", shown, what);
        }
        lex_advance(P);
    }
    return BSP_OK;
}

/* --- records ---------------------------------------------------------------- */

/* The v block; its keyword (on line VLINE) is consumed. */
static bsp_status read_view(parser *P, size_t vline)
{
    static const keyword order[] = {KW_FROM, KW_AT, KW_UP, KW_ANGLE, KW_HITHER, KW_RESOLUTION};
    static const size_t count[] = {3, 3, 3, 1, 1, 2};
    double vals[6][3];
    long long res[2] = {0, 0};
    size_t res_line = vline, angle_line = vline;
    char shown[SHOW_SIZE], what[64];
    if (P->v_line)
        return fail(P, BSP_ERR_PARSE, vline, "second 'v' block (the first is on line %zu)",
                    P->v_line);
    P->v_line = vline;

    for (size_t k = 0; k < 6; k++) {
        const token t = P->tok;
        const char *want = keyword_name[order[k]];
        if (token_keyword(&t) != order[k]) {
            token_show(&t, shown, sizeof shown);
            if (!t.s)
                return fail(P, BSP_ERR_PARSE, vline,
                            "truncated 'v' block: expected '%s', found end of input", want);
            return fail(P, BSP_ERR_PARSE, t.line, "'v' block: expected '%s', found %s", want,
                        shown);
        }
        lex_advance(P);
        snprintf(what, sizeof what, "'%s' line of the 'v' block", want);
        if (order[k] == KW_ANGLE)
            angle_line = t.line;
        if (order[k] != KW_RESOLUTION) {
            bsp_status st = read_numbers(P, what, t.line, count[k], vals[k], count[k]);
            if (st != BSP_OK)
                return st;
            continue;
        }
        res_line = t.line;
        for (int i = 0; i < 2; i++) {
            const token r = P->tok;
            if (!r.s || token_keyword(&r) != KW_NONE)
                return truncated(P, what, t.line, 2, &r);
            if (!parse_integer(&r, &res[i])) {
                token_show(&r, shown, sizeof shown);
                if (mesh_parse_number(r.s, r.len, &vals[5][0]) == MESH_NUM_NONFINITE)
                    return fail(P, BSP_ERR_INVALID, r.line, "non-finite number %s in %s", shown,
                                what);
                return fail(P, BSP_ERR_PARSE, r.line,
                            "resolution must be a whole number of pixels, found %s", shown);
            }
            lex_advance(P);
        }
    }

    double angle = vals[3][0];
    if (!(angle > 0 && angle < 180))
        return fail(P, BSP_ERR_INVALID, angle_line, "camera: angle %g is outside (0, 180) degrees",
                    angle);
    for (int i = 0; i < 2; i++) {
        if (res[i] > INT_MAX)
            return fail(P, BSP_ERR_LIMIT, res_line, "camera: resolution %lld is out of range",
                        res[i]);
        if (res[i] <= 0)
            return fail(P, BSP_ERR_INVALID, res_line,
                        "camera: resolution %lld x %lld is not positive", res[0], res[1]);
    }
    bsp_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.from = bsp_v3(vals[0][0], vals[0][1], vals[0][2]);
    cam.at = bsp_v3(vals[1][0], vals[1][1], vals[1][2]);
    cam.up = bsp_v3(vals[2][0], vals[2][1], vals[2][2]);
    cam.angle_deg = angle;
    cam.hither = vals[4][0];
    cam.res_x = (int)res[0];
    cam.res_y = (int)res[1];
    scene_set_source(P->scene, P->name, vline);
    return bsp_scene_set_camera(P->scene, &cam, P->err);
}

/* A p (PER = 3) or pp (PER = 6) record; its keyword (on line LINE) is
 * consumed. */
static bsp_status read_polygon(parser *P, keyword kw, size_t line)
{
    const size_t per = kw == KW_P ? 3 : 6;
    const char *what = kw == KW_P ? "'p' record" : "'pp' record";
    const token ct = P->tok;
    char shown[SHOW_SIZE];
    long long n;
    if (!ct.s || token_keyword(&ct) != KW_NONE) {
        token_show(&ct, shown, sizeof shown);
        return fail(P, BSP_ERR_PARSE, line, "truncated %s: expected a vertex count, found %s", what,
                    shown);
    }
    if (!parse_integer(&ct, &n)) {
        token_show(&ct, shown, sizeof shown);
        return fail(P, BSP_ERR_PARSE, ct.line,
                    "polygon vertex count must be a whole number, found %s", shown);
    }
    if (n <= 0)
        return fail(P, BSP_ERR_PARSE, ct.line,
                    "polygon vertex count must be at least 1, found %lld", n);
    if ((unsigned long long)n > SCENE_MAX_POLY_VERTS)
        return fail(P, BSP_ERR_LIMIT, ct.line, "polygon with %lld vertices (the limit is %zu)", n,
                    SCENE_MAX_POLY_VERTS);
    lex_advance(P);
    /* Each number takes at least one byte and one separator: refuse counts
     * that cannot fit before allocating anything. */
    size_t nv = (size_t)n, numbers = nv * per;
    size_t remain = P->tok.s ? (size_t)(P->end - P->tok.s) : 0;
    if (2 * numbers - 1 > remain)
        return fail(P, BSP_ERR_PARSE, line,
                    "truncated %s: %zu vertices need %zu numbers, but only %zu bytes remain", what,
                    nv, numbers, remain);
    size_t need = kw == KW_P ? nv : 2 * nv;
    if (need > P->vcap) {
        size_t ncap = P->vcap ? P->vcap : 64;
        while (ncap < need)
            ncap *= 2;
        bsp_vec3 *nb = realloc(P->vbuf, ncap * sizeof *nb);
        if (!nb)
            return fail(P, BSP_ERR_NOMEM, line, "out of memory");
        P->vbuf = nb;
        P->vcap = ncap;
    }
    bsp_vec3 *verts = P->vbuf, *normals = kw == KW_PP ? P->vbuf + nv : NULL;
    for (size_t i = 0; i < nv; i++) {
        double x[6];
        bsp_status st = read_numbers(P, what, line, numbers, x, per);
        if (st != BSP_OK)
            return st;
        verts[i] = bsp_v3(x[0], x[1], x[2]);
        if (normals)
            normals[i] = bsp_v3(x[3], x[4], x[5]);
    }
    scene_set_source(P->scene, P->name, line);
    if (normals)
        return bsp_scene_add_patch(P->scene, verts, normals, nv, P->err);
    return bsp_scene_add_polygon(P->scene, verts, nv, P->err);
}

/* Counts an 'f' record whose largest number of KIND, V, is above 1. */
static void note_range(parser *P, int kind, double v, size_t line)
{
    if (!(v > 1.0))
        return;
    if (P->out_of_range[kind].count++ == 0) {
        P->out_of_range[kind].line = line;
        P->out_of_range[kind].value = v;
    }
}

/* The warnings of note_range, once per kind. */
static void warn_ranges(parser *P)
{
    static const char *const what[MATERIAL_RANGE_KINDS] = {
        "a colour component above 1 (NFF colours run from 0 to 1)",
        "Kd or Ks above 1 (usually 0 to 1): surfaces may reflect more light than reaches them",
        ("a transmittance T above 1 (T is the fraction of the transmitted ray's light): "
         "pixels may overflow")};
    for (int k = 0; k < MATERIAL_RANGE_KINDS; k++) {
        size_t c = P->out_of_range[k].count;
        if (c)
            scene_warn(P->scene, "%s:%zu: %zu 'f' record%s with %s; the first has %g", P->name,
                       P->out_of_range[k].line, c, c == 1 ? "" : "s", what[k],
                       P->out_of_range[k].value);
    }
}

/* One record starting with the keyword token K (already consumed). */
static bsp_status read_record(parser *P, const token *k)
{
    double x[8];
    bsp_status st;
    char shown[SHOW_SIZE];
    keyword kw = token_keyword(k);
    scene_set_source(P->scene, P->name, k->line);
    switch (kw) {
    case KW_V:
        return read_view(P, k->line);
    case KW_B:
        if ((st = read_numbers(P, "'b' record", k->line, 3, x, 3)) != BSP_OK)
            return st;
        if (x[0] < 0 || x[1] < 0 || x[2] < 0)
            return fail(P, BSP_ERR_INVALID, k->line, "background: negative colour");
        bsp_scene_set_background(P->scene, x);
        return BSP_OK;
    case KW_L: {
        bsp_light light;
        memset(&light, 0, sizeof light);
        if ((st = read_numbers(P, "'l' record", k->line, 3, x, 3)) != BSP_OK)
            return st;
        size_t n = looks_numeric(&P->tok) ? 6 : 3; /* a colour follows */
        if (n == 6 && (st = read_numbers(P, "'l' record", k->line, 6, x + 3, 3)) != BSP_OK)
            return st;
        light.pos = bsp_v3(x[0], x[1], x[2]);
        for (int i = 0; i < 3; i++)
            light.color[i] = n == 6 ? x[3 + i] : 1.0;
        light.has_color = n == 6;
        return bsp_scene_add_light(P->scene, &light, P->err);
    }
    case KW_F: {
        if ((st = read_numbers(P, "'f' record", k->line, 8, x, 8)) != BSP_OK)
            return st;
        bsp_material m = {{x[0], x[1], x[2]}, x[3], x[4], x[5], x[6], x[7], 0};
        note_range(P, RANGE_COLOUR, fmax(x[0], fmax(x[1], x[2])), k->line);
        note_range(P, RANGE_KD_KS, fmax(x[3], x[4]), k->line);
        note_range(P, RANGE_T, x[6], k->line);
        return bsp_scene_set_material(P->scene, &m, P->err);
    }
    case KW_C:
        if ((st = read_numbers(P, "'c' record", k->line, 8, x, 8)) != BSP_OK)
            return st;
        return bsp_scene_add_cone(P->scene, bsp_v3(x[0], x[1], x[2]), x[3],
                                  bsp_v3(x[4], x[5], x[6]), x[7], P->err);
    case KW_S:
        if ((st = read_numbers(P, "'s' record", k->line, 4, x, 4)) != BSP_OK)
            return st;
        return bsp_scene_add_sphere(P->scene, bsp_v3(x[0], x[1], x[2]), x[3], P->err);
    case KW_P:
    case KW_PP:
        return read_polygon(P, kw, k->line);
    case KW_FROM:
    case KW_AT:
    case KW_UP:
    case KW_ANGLE:
    case KW_HITHER:
    case KW_RESOLUTION:
        return fail(P, BSP_ERR_PARSE, k->line, "'%s' outside a 'v' block", keyword_name[kw]);
    case KW_NONE:
        break;
    }
    token_show(k, shown, sizeof shown);
    if (looks_numeric(k))
        return fail(P, BSP_ERR_PARSE, k->line,
                    "unexpected number %s where a keyword was expected (too many numbers in "
                    "the record before?)",
                    shown);
    return fail(P, BSP_ERR_PARSE, k->line, "unknown keyword %s", shown);
}

/* Parses plain NFF text BUF[0..LEN). */
static bsp_status parse_nff(const char *buf, size_t len, const char *name, bsp_scene **out,
                            bsp_error *err)
{
    parser P;
    memset(&P, 0, sizeof P);
    P.name = name;
    P.p = buf;
    P.end = buf + len;
    P.line = 1;
    P.err = err;
    P.scene = bsp_scene_create();
    if (!P.scene)
        return error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory");
    lex_advance(&P);
    bsp_status st = BSP_OK;
    while (P.tok.s) {
        token k = P.tok;
        lex_advance(&P);
        if ((st = read_record(&P, &k)) != BSP_OK)
            break;
    }
    free(P.vbuf);
    if (st != BSP_OK) {
        bsp_scene_destroy(P.scene);
        return st;
    }
    warn_ranges(&P);
    scene_set_source(P.scene, name, 0);
    scene_finish(P.scene);
    scene_set_source(P.scene, NULL, 0); /* NAME is borrowed only for the call */
    *out = P.scene;
    return BSP_OK;
}

/* --- gzip and files ------------------------------------------------------------ */

static int is_gzip(const char *buf, size_t len, const char *name)
{
    size_t n = strlen(name);
    if (n >= 3 && strcmp(name + n - 3, ".gz") == 0)
        return 1;
    return scene_is_gzip(buf, len);
}

static bsp_status load_buffer(const char *buf, size_t len, const char *name, bsp_scene **out,
                              bsp_error *err)
{
    if (len > NFF_MAX_INPUT)
        return error_set(err, BSP_ERR_LIMIT, name, 0, "input is larger than %zu bytes",
                         NFF_MAX_INPUT);
    return scene_parse_maybe_gzip(parse_nff, buf, len, name, NFF_MAX_INPUT, is_gzip(buf, len, name),
                                  out, err);
}

/* --- public ----------------------------------------------------------------- */

bsp_status bsp_scene_load_nff_memory(const char *buf, size_t len, const char *name, bsp_scene **out,
                                     bsp_error *err)
{
    if (!out)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "bsp_scene_load_nff_memory: no output pointer");
    *out = NULL;
    if (!name)
        name = "<memory>";
    if (!buf && len)
        return error_set(err, BSP_ERR_INVALID, name, 0, "no buffer");
    if (!buf)
        buf = "";
    return load_buffer(buf, len, name, out, err);
}

bsp_status nff_load_file(const char *path, bsp_scene **out, bsp_error *err)
{
    return mesh_load_file(load_buffer, path, out, err); /* the meshes' 2 GiB read limit */
}
