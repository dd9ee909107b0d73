/*
 * obj.c — the Wavefront OBJ reader (polygonal subset), the helpers shared
 * with the PLY reader (mesh.h), and bsp_scene_set_default_view.
 *
 * Input is held whole in memory; files larger than 2 GiB are refused before
 * reading. The text is read statement by statement. A statement is one line;
 * a backslash at the very end of a line (before LF or CRLF) joins the next
 * line to it. '#' starts a comment that runs to the end of the physical line.
 * Lines end with LF or CRLF; other whitespace is space, tab, CR, VT and FF.
 *
 * Grammar accepted (N: a decimal number as in NFF — [+-]digits[.digits]
 * [(e|E)[+-]digits], no hex, nan or inf; I: a non-zero integer [+-]?[0-9]+):
 *   statement := 'v' N N N [N | N N N]  -- vertex: x y z, optional w (ignored)
 *                                          or the common x y z r g b colour
 *                                          extension (colour ignored)
 *              | 'vn' N N N              -- vertex normal
 *              | 'vt' N [N [N]]          -- texture coordinate (validated, unused)
 *              | 'f' ref ref ref ref*    -- face: one primitive, any vertex count
 *              | 'g' ... | 'o' ... | 's' ... | 'usemtl' ... | 'mtllib' ...
 *                                        -- accepted and ignored, no warning
 *              | unsupported OBJ statement ...
 *                                        -- ignored, one warning per keyword
 *                                           (l p vp cstype deg bmat step curv
 *                                           curv2 surf parm trim hole scrv sp
 *                                           end con mg bevel c_interp d_interp
 *                                           lod usemap maplib shadow_obj
 *                                           trace_obj ctech stech call csh)
 *   ref := I | I '/' I | I '//' I | I '/' I '/' I   -- v, v/vt, v//vn, v/vt/vn
 *   A positive index counts from 1 among the vertices (normals, texture
 *   coordinates) defined so far; a negative one counts back from the last
 *   one defined (-1 is the last). Forward references are refused.
 *   A face whose every corner names a normal becomes a patch (vertex normals),
 *   otherwise a polygon. Corners of one face may differ in naming a texture
 *   coordinate (unused) but not in naming a normal (patch or polygon would be
 *   ambiguous). Any other keyword is an error.
 *
 * Errors: each failure returns a status and "NAME:LINE: what is wrong", LINE
 * being the physical line of the offending token, or of the statement's
 * keyword for a statement that is cut short or has the wrong number of
 * values. Malformed text and bad references are BSP_ERR_PARSE, non-finite
 * numbers BSP_ERR_INVALID, absurd sizes BSP_ERR_LIMIT; I/O errors are
 * "NAME: ..." alone. Degenerate faces are not errors: the builder drops them
 * with one warning per kind. On failure *out is NULL and nothing is kept.
 * A mesh has no camera or light: the default view is set at the end (see
 * bsp_scene_set_default_view and docs/formats.md).
 */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "geom/vec.h"
#include "scene/mesh.h"
#include "scene/scene_internal.h"
#include "util/errno_text.h"

/* ===================== helpers shared with ply.c (mesh.h) ===================== */

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

/* Clinger's fast path is exact only when double arithmetic is not carried
 * out in a wider format. */
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD == 0
#define MESH_FAST_PATH 1
#else
#define MESH_FAST_PATH 0
#endif

static const double exact_pow10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                       1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                       1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

static int lower(char c)
{
    return c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c;
}

/* Case-insensitive comparison of S[0..LEN) with the lower-case WORD. */
static int word_is(const char *s, size_t len, const char *word)
{
    size_t n = strlen(word);
    if (len != n)
        return 0;
    for (size_t i = 0; i < n; i++)
        if (lower(s[i]) != word[i])
            return 0;
    return 1;
}

mesh_number mesh_parse_number(const char *s, size_t len, double *out)
{
    size_t i = 0;
    int neg = 0;
    if (i < len && (s[i] == '+' || s[i] == '-')) {
        neg = s[i] == '-';
        i++;
    }
    const size_t body = i;
    uint64_t mant = 0;
    int ndig = 0, slow = 0, any = 0;
    long exp10 = 0;
    for (; i < len && is_digit(s[i]); i++) {
        any = 1;
        unsigned d = (unsigned)(s[i] - '0');
        if (mant || d) {
            if (ndig == 19) {
                slow = 1;
            } else {
                mant = mant * 10 + d;
                ndig++;
            }
        }
    }
    if (i < len && s[i] == '.') {
        i++;
        for (; i < len && is_digit(s[i]); i++) {
            any = 1;
            unsigned d = (unsigned)(s[i] - '0');
            if (mant || d) {
                if (ndig == 19) {
                    slow = 1;
                    continue;
                }
                mant = mant * 10 + d;
                ndig++;
            }
            exp10--;
        }
    }
    if (!any) {
        const char *w = s + body;
        size_t wl = len - body;
        if (word_is(w, wl, "nan") || word_is(w, wl, "inf") || word_is(w, wl, "infinity") ||
            (wl >= 5 && word_is(w, 4, "nan(") && w[wl - 1] == ')'))
            return MESH_NUM_NONFINITE;
        return MESH_NUM_MALFORMED;
    }
    if (i < len && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        int eneg = 0;
        if (i < len && (s[i] == '+' || s[i] == '-')) {
            eneg = s[i] == '-';
            i++;
        }
        if (i >= len || !is_digit(s[i]))
            return MESH_NUM_MALFORMED;
        long e = 0;
        for (; i < len && is_digit(s[i]); i++)
            if (e < 100000)
                e = e * 10 + (s[i] - '0');
        exp10 += eneg ? -e : e;
    }
    if (i != len)
        return MESH_NUM_MALFORMED;
    if (mant == 0 && !slow) {
        *out = neg ? -0.0 : 0.0;
        return MESH_NUM_OK;
    }
#if MESH_FAST_PATH
    if (!slow && mant <= ((uint64_t)1 << 53) && exp10 >= -22 && exp10 <= 22) {
        double v = (double)mant;
        v = exp10 < 0 ? v / exact_pow10[-exp10] : v * exact_pow10[exp10];
        *out = neg ? -v : v;
        return MESH_NUM_OK;
    }
#else
    (void)exact_pow10;
#endif
    char small[128];
    char *copy = small;
    if (len >= sizeof small) {
        copy = malloc(len + 1);
        if (!copy)
            return MESH_NUM_MALFORMED;
    }
    memcpy(copy, s, len);
    copy[len] = '\0';
    char *endp;
    double v = strtod(copy, &endp);
    int whole = endp == copy + len;
    if (copy != small)
        free(copy);
    if (!whole)
        return MESH_NUM_MALFORMED;
    if (!isfinite(v))
        return MESH_NUM_NONFINITE;
    *out = v;
    return MESH_NUM_OK;
}

int mesh_parse_integer(const char *s, size_t len, long long *out)
{
    size_t i = 0;
    int neg = 0;
    if (i < len && (s[i] == '+' || s[i] == '-')) {
        neg = s[i] == '-';
        i++;
    }
    if (i == len)
        return 0;
    long long v = 0;
    for (; i < len; i++) {
        if (!is_digit(s[i]))
            return 0;
        /* saturate without overflowing: v stays below 10^18 + 9 */
        v = v < 100000000000000000LL ? v * 10 + (s[i] - '0') : 1000000000000000000LL;
    }
    *out = neg ? -v : v;
    return 1;
}

const char *mesh_show_token(const char *s, size_t len, char *buf, size_t size)
{
    if (!s) {
        snprintf(buf, size, "end of line");
        return buf;
    }
    size_t n = 0, limit = size - 8; /* room for the quotes, "..." and NUL */
    buf[n++] = '\'';
    size_t i;
    for (i = 0; i < len && n + 4 <= limit; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c >= 0x20 && c < 0x7f && c != '\'' && c != '\\') {
            buf[n++] = (char)c;
        } else {
            snprintf(buf + n, size - n, "\\x%02x", c);
            n += 4;
        }
    }
    if (i < len) {
        memcpy(buf + n, "...", 3);
        n += 3;
    }
    buf[n++] = '\'';
    buf[n] = '\0';
    return buf;
}

bsp_status mesh_open_file(const char *path, FILE **fp_out, size_t *cap_out, bsp_error *err)
{
    *fp_out = NULL;
    if (!path)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "no scene file given");
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return error_set(err, BSP_ERR_IO, path, 0, "cannot open: %s", ERRNO_TEXT(errno));
    size_t cap = (size_t)1 << 16;
    struct stat st;
    if (fstat(fileno(fp), &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            fclose(fp);
            return error_set(err, BSP_ERR_IO, path, 0, "cannot open: %s", ERRNO_TEXT(EISDIR));
        }
        if (S_ISREG(st.st_mode)) {
            if ((uintmax_t)st.st_size > MESH_MAX_INPUT) {
                fclose(fp);
                return error_set(err, BSP_ERR_LIMIT, path, 0, "file is larger than %zu bytes (%jd)",
                                 MESH_MAX_INPUT, (intmax_t)st.st_size);
            }
            cap = (size_t)st.st_size + 1; /* +1: end of file seen without a regrow */
        }
    }
    *fp_out = fp;
    *cap_out = cap;
    return BSP_OK;
}

bsp_status mesh_read_file(const char *path, char **out, size_t *outlen, bsp_error *err)
{
    FILE *fp;
    size_t cap;
    bsp_status opened = mesh_open_file(path, &fp, &cap, err);
    if (opened != BSP_OK)
        return opened;
    char *buf = malloc(cap);
    size_t used = 0;
    if (!buf) {
        fclose(fp);
        return error_set(err, BSP_ERR_NOMEM, path, 0, "out of memory");
    }
    for (;;) {
        if (used == cap) {
            if (cap > MESH_MAX_INPUT) {
                free(buf);
                fclose(fp);
                return error_set(err, BSP_ERR_LIMIT, path, 0, "file is larger than %zu bytes",
                                 MESH_MAX_INPUT);
            }
            size_t ncap = cap * 2 > MESH_MAX_INPUT + 1 ? MESH_MAX_INPUT + 1 : cap * 2;
            char *nb = realloc(buf, ncap);
            if (!nb) {
                free(buf);
                fclose(fp);
                return error_set(err, BSP_ERR_NOMEM, path, 0, "out of memory");
            }
            buf = nb;
            cap = ncap;
        }
        size_t got = fread(buf + used, 1, cap - used, fp);
        used += got;
        if (got == 0 || used < cap) {
            if (ferror(fp)) {
                int e = errno;
                free(buf);
                fclose(fp);
                return error_set(err, BSP_ERR_IO, path, 0, "read error: %s", ERRNO_TEXT(e));
            }
            if (feof(fp))
                break;
        }
    }
    fclose(fp);
    if (used > MESH_MAX_INPUT) {
        free(buf);
        return error_set(err, BSP_ERR_LIMIT, path, 0, "file is larger than %zu bytes",
                         MESH_MAX_INPUT);
    }
    *out = buf;
    *outlen = used;
    return BSP_OK;
}

bsp_status mesh_load_memory(mesh_parse_fn parse, const char *buf, size_t len, const char *name,
                            bsp_scene **out, bsp_error *err)
{
    if (!out)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "no output pointer");
    *out = NULL;
    if (!name)
        name = "<memory>";
    if (!buf && len)
        return error_set(err, BSP_ERR_INVALID, name, 0, "no buffer");
    if (len > MESH_MAX_INPUT)
        return error_set(err, BSP_ERR_LIMIT, name, 0, "input is larger than %zu bytes",
                         MESH_MAX_INPUT);
    return parse(buf ? buf : "", len, name, out, err);
}

bsp_status mesh_load_file(mesh_parse_fn parse, const char *path, bsp_scene **out,
                          bsp_error *err)
{
    if (!out)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "no output pointer");
    *out = NULL;
    if (!path)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "no path");
    char *buf = NULL;
    size_t len = 0;
    bsp_status st = mesh_read_file(path, &buf, &len, err);
    if (st != BSP_OK)
        return st;
    st = parse(buf, len, path, out, err);
    free(buf);
    return st;
}

/* White, mostly diffuse, with a little specular highlight. */
static const bsp_material mesh_material = {{1.0, 1.0, 1.0}, 0.8, 0.1, 30.0, 0.0, 1.0, 1};

bsp_scene *mesh_scene_create(void)
{
    bsp_scene *s = bsp_scene_create();
    if (!s)
        return NULL;
    if (bsp_scene_set_material(s, &mesh_material, NULL) != BSP_OK) {
        bsp_scene_destroy(s);
        return NULL;
    }
    return s;
}

bsp_status mesh_finish(bsp_scene *s, const char *name, bsp_error *err)
{
    scene_set_source(s, name, 0);
    bsp_status st = bsp_scene_set_default_view(s, NULL, NULL, NULL, 0.0, err);
    if (st == BSP_OK)
        scene_finish(s);
    scene_set_source(s, NULL, 0); /* NAME is borrowed only for the call */
    return st;
}

/* --- the default view ------------------------------------------------------------ */

static int same_point(bsp_vec3 a, bsp_vec3 b)
{
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

bsp_status bsp_scene_set_default_view(bsp_scene *s, const bsp_vec3 *eye, const bsp_vec3 *at,
                                      const bsp_vec3 *up, double fov_deg, bsp_error *err)
{
    if (!s)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "default view: no scene");
    if (fov_deg == 0.0)
        fov_deg = MESH_DEFAULT_FOV;
    if (!(fov_deg > 0.0 && fov_deg < 180.0))
        return scene_fail(s, err, BSP_ERR_INVALID,
                          "default view: field of view %g is outside (0, 180) degrees", fov_deg);
    if ((eye && !v3_is_finite(*eye)) || (at && !v3_is_finite(*at)) || (up && !v3_is_finite(*up)))
        return scene_fail(s, err, BSP_ERR_INVALID, "default view: non-finite number");

    /* the bounding sphere of the bounding box (a unit sphere at the origin
     * for an empty scene); halves first so that nothing overflows */
    bsp_vec3 centre = bsp_v3(0, 0, 0);
    double radius = 1.0;
    bsp_box b = s->bounds;
    if (!box_is_empty(b)) {
        double h[3], m = 0.0;
        for (int k = 0; k < 3; k++) {
            centre.v[k] = 0.5 * b.lo.v[k] + 0.5 * b.hi.v[k];
            h[k] = 0.5 * b.hi.v[k] - 0.5 * b.lo.v[k];
            m = fmax(m, h[k]);
        }
        if (m > 0.0) {
            double q = 0.0;
            for (int k = 0; k < 3; k++)
                q += (h[k] / m) * (h[k] / m);
            radius = m * sqrt(q);
        } else {
            radius = fmax(1e-300, fabs(centre.x) + fabs(centre.y) + fabs(centre.z)) * 1e-6;
        }
    }

    bsp_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.at = at ? *at : centre;
    if (eye) {
        cam.from = *eye;
    } else {
        /* far enough that the bounding sphere fits in the cone of the view
         * angle; for a displaced 'at', a sphere around 'at' that holds it */
        double half = fov_deg * (BSP_PI / 360.0);
        double dist = (radius + v3_length(v3_sub(cam.at, centre))) / sin(half);
        const double k = 0.57735026918962576; /* 1 / sqrt(3) */
        cam.from = v3_madd(cam.at, bsp_v3(k, k, k), dist);
    }
    if (!v3_is_finite(cam.from))
        return scene_fail(s, err, BSP_ERR_INVALID,
                          "default view: the scene is too large to frame (radius %g)", radius);
    if (up) {
        cam.up = *up;
    } else {
        bsp_vec3 dir = v3_normalize(v3_sub(cam.at, cam.from));
        cam.up = v3_length(v3_cross(dir, bsp_v3(0, 0, 1))) > 1e-6 ? bsp_v3(0, 0, 1)
                                                                  : bsp_v3(0, 1, 0);
    }
    cam.angle_deg = fov_deg;
    cam.hither = 0.0;
    cam.res_x = s->has_camera ? s->camera.res_x : MESH_DEFAULT_RES;
    cam.res_y = s->has_camera ? s->camera.res_y : MESH_DEFAULT_RES;

    bsp_camera old = s->camera;
    int had_camera = s->has_camera, had_default = s->camera_is_default;
    bsp_status st = bsp_scene_set_camera(s, &cam, err);
    if (st != BSP_OK)
        return st;
    s->camera_is_default = 1;

    /* the light at the eye: added to a scene without lights, moved when it
     * sat at the previous eye (as this function put it) */
    if (s->nlights == 0) {
        bsp_light light;
        memset(&light, 0, sizeof light);
        light.pos = cam.from;
        light.color[0] = light.color[1] = light.color[2] = 1.0;
        st = bsp_scene_add_light(s, &light, err);
        if (st != BSP_OK) {
            s->camera = old;
            s->has_camera = had_camera;
            s->camera_is_default = had_default;
        }
        return st;
    }
    if (had_camera)
        for (size_t i = 0; i < s->nlights; i++)
            if (same_point(s->lights[i].pos, old.from))
                s->lights[i].pos = cam.from;
    return BSP_OK;
}

/* ============================== the OBJ reader ============================== */

typedef struct token {
    const char *s; /* first byte */
    size_t len;
    size_t line; /* physical line of the first byte */
} token;

/* OBJ statements that are ignored with one warning per keyword. */
static const struct {
    const char *kw, *why;
} obj_unsupported[] = {
    {"l", "lines are not surfaces"},
    {"p", "points are not surfaces"},
    {"vp", "free-form geometry is not supported"},
    {"cstype", "free-form geometry is not supported"},
    {"deg", "free-form geometry is not supported"},
    {"bmat", "free-form geometry is not supported"},
    {"step", "free-form geometry is not supported"},
    {"curv", "free-form geometry is not supported"},
    {"curv2", "free-form geometry is not supported"},
    {"surf", "free-form geometry is not supported"},
    {"parm", "free-form geometry is not supported"},
    {"trim", "free-form geometry is not supported"},
    {"hole", "free-form geometry is not supported"},
    {"scrv", "free-form geometry is not supported"},
    {"sp", "free-form geometry is not supported"},
    {"end", "free-form geometry is not supported"},
    {"con", "free-form geometry is not supported"},
    {"mg", "merging groups are not supported"},
    {"bevel", "display attributes are not supported"},
    {"c_interp", "display attributes are not supported"},
    {"d_interp", "display attributes are not supported"},
    {"lod", "display attributes are not supported"},
    {"usemap", "texture maps are not supported"},
    {"maplib", "texture maps are not supported"},
    {"shadow_obj", "display attributes are not supported"},
    {"trace_obj", "display attributes are not supported"},
    {"ctech", "display attributes are not supported"},
    {"stech", "display attributes are not supported"},
    {"call", "other files are not read"},
    {"csh", "commands are never run"},
};
#define OBJ_UNSUPPORTED (sizeof obj_unsupported / sizeof obj_unsupported[0])

typedef struct obj_parser {
    const char *name;
    const char *p, *end;
    size_t line; /* physical line at p */
    bsp_scene *scene;
    bsp_error *err;
    bsp_vec3 *v, *vn;
    size_t nv, cap_v, nvn, cap_vn, nvt;
    bsp_vec3 *fv, *fn; /* corners of the current face */
    size_t cap_f;
    size_t ignored[OBJ_UNSUPPORTED], ignored_line[OBJ_UNSUPPORTED];
} obj_parser;

static void fail_record(obj_parser *P, bsp_status status, size_t line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* Records a parse error on LINE and yields STATUS (see FAIL_WITH). */
#define fail(P, status, line, ...) FAIL_WITH(status, fail_record((P), (status), (line), __VA_ARGS__))

static void fail_record(obj_parser *P, bsp_status status, size_t line, const char *fmt, ...)
{
    char msg[BSP_ERROR_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    error_record(P->err, status, P->name, line, "%s", msg);
}

static int is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* Length of the line continuation at P ("\\\n", "\\\r\n", or a backslash
 * (and CR) at the end of input), 0 if there is none. */
static size_t continuation(const char *p, const char *end)
{
    if (*p != '\\')
        return 0;
    const char *q = p + 1;
    if (q < end && *q == '\r')
        q++;
    if (q == end)
        return (size_t)(q - p);
    return *q == '\n' ? (size_t)(q + 1 - p) : 0;
}

/* The next token of the current statement into *T; 0 at the end of the
 * statement (a newline, a comment or the end of input, not consumed). */
static int next_token(obj_parser *P, token *t)
{
    const char *p = P->p, *end = P->end;
    for (;;) {
        while (p < end && is_blank(*p))
            p++;
        size_t c;
        if (p < end && (c = continuation(p, end)) != 0) {
            if (p[c - 1] == '\n')
                P->line++;
            p += c;
            continue;
        }
        break;
    }
    P->p = p;
    if (p == end || *p == '\n' || *p == '#')
        return 0;
    const char *s = p;
    while (p < end && !is_blank(*p) && *p != '\n' && *p != '#' && !continuation(p, end))
        p++;
    t->s = s;
    t->len = (size_t)(p - s);
    t->line = P->line;
    P->p = p;
    return 1;
}

/* Skips what remains of the statement (tokens, a comment) and its newline. */
static void end_statement(obj_parser *P)
{
    token t;
    while (next_token(P, &t))
        ;
    if (P->p < P->end && *P->p == '#') {
        const char *nl = memchr(P->p, '\n', (size_t)(P->end - P->p));
        P->p = nl ? nl : P->end;
    }
    if (P->p < P->end) { /* at '\n' */
        P->p++;
        P->line++;
    }
}

static int token_is(const token *t, const char *word)
{
    size_t n = strlen(word);
    return t->len == n && memcmp(t->s, word, n) == 0;
}

/* Reads the numbers of a statement (keyword WHAT on line KLINE, already
 * consumed) into X: at least MIN, at most MAX; *N gets how many. */
static bsp_status read_values(obj_parser *P, const char *what, size_t kline, double *x,
                              size_t min, size_t max, size_t *n)
{
    char shown[MESH_SHOW_SIZE];
    token t;
    size_t i = 0;
    while (next_token(P, &t)) {
        if (i == max)
            return fail(P, BSP_ERR_PARSE, t.line, "extra value %s in '%s' statement (at most %zu)",
                        mesh_show_token(t.s, t.len, shown, sizeof shown), what, max);
        mesh_number r = mesh_parse_number(t.s, t.len, &x[i]);
        if (r == MESH_NUM_NONFINITE)
            return fail(P, BSP_ERR_INVALID, t.line, "non-finite number %s in '%s' statement",
                        mesh_show_token(t.s, t.len, shown, sizeof shown), what);
        if (r != MESH_NUM_OK)
            return fail(P, BSP_ERR_PARSE, t.line, "malformed number %s in '%s' statement",
                        mesh_show_token(t.s, t.len, shown, sizeof shown), what);
        i++;
    }
    if (i < min)
        return fail(P, BSP_ERR_PARSE, kline,
                    "truncated '%s' statement: expected %s%zu number%s, found %zu", what,
                    min < max ? "at least " : "", min, min == 1 ? "" : "s", i);
    *n = i;
    return BSP_OK;
}

/* Appends X to the array *A (count *N, capacity *CAP) of WHAT. */
static bsp_status push_vec(obj_parser *P, bsp_vec3 **a, size_t *n, size_t *cap, bsp_vec3 x,
                           const char *what, size_t line)
{
    if (*n >= MESH_MAX_VERTS)
        return fail(P, BSP_ERR_LIMIT, line, "more than %zu %s", MESH_MAX_VERTS, what);
    if (*n == *cap) {
        size_t ncap = *cap ? *cap * 2 : 1024;
        bsp_vec3 *na = realloc(*a, ncap * sizeof *na);
        if (!na)
            return fail(P, BSP_ERR_NOMEM, line, "out of memory");
        *a = na;
        *cap = ncap;
    }
    (*a)[(*n)++] = x;
    return BSP_OK;
}

/* Resolves the OBJ index I (written PART in the corner T) of WHAT among
 * COUNT defined so far into *OUT. */
static bsp_status resolve(obj_parser *P, const token *t, const char *part, size_t plen,
                          long long i, size_t count, const char *what, size_t *out)
{
    char shown[MESH_SHOW_SIZE], shown_part[MESH_SHOW_SIZE];
    if (i > 0 && (unsigned long long)i <= count) {
        *out = (size_t)i - 1;
        return BSP_OK;
    }
    if (i < 0 && (unsigned long long)-i <= count) {
        *out = count - (size_t)-i;
        return BSP_OK;
    }
    mesh_show_token(part, plen, shown_part, sizeof shown_part);
    mesh_show_token(t->s, t->len, shown, sizeof shown);
    if (i == 0)
        return fail(P, BSP_ERR_PARSE, t->line,
                    "%s index %s in %s is invalid (indices start at 1; negative ones count back "
                    "from the last)",
                    what, shown_part, shown);
    return fail(P, BSP_ERR_PARSE, t->line, "%s index %s in %s is out of range (%zu defined so far)",
                what, shown_part, shown, count);
}

enum { REF_VT = 1, REF_VN = 2 };

/* Reads one face corner T: its vertex (and normal, when it names one, else
 * *VN = SIZE_MAX); returns its form (REF_* bits) in *FORM. */
static bsp_status read_ref(obj_parser *P, const token *t, size_t *v, size_t *vn, int *form)
{
    char shown[MESH_SHOW_SIZE];
    const char *part[3];
    size_t plen[3], nparts = 0;
    const char *s = t->s, *e = t->s + t->len;
    for (;;) {
        const char *slash = memchr(s, '/', (size_t)(e - s));
        const char *stop = slash ? slash : e;
        if (nparts == 3)
            goto malformed;
        part[nparts] = s;
        plen[nparts++] = (size_t)(stop - s);
        if (!slash)
            break;
        s = slash + 1;
    }
    long long idx[3] = {0, 0, 0};
    int have[3] = {0, 0, 0};
    for (size_t k = 0; k < nparts; k++) {
        if (plen[k] == 0) {
            if (k == 1 && nparts == 3)
                continue; /* v//vn */
            goto malformed;
        }
        if (!mesh_parse_integer(part[k], plen[k], &idx[k]))
            goto malformed;
        have[k] = 1;
    }
    bsp_status st = resolve(P, t, part[0], plen[0], idx[0], P->nv, "vertex", v);
    if (st != BSP_OK)
        return st;
    size_t unused;
    if (have[1] && (st = resolve(P, t, part[1], plen[1], idx[1], P->nvt, "texture coordinate",
                                 &unused)) != BSP_OK)
        return st;
    *vn = SIZE_MAX;
    if (have[2] &&
        (st = resolve(P, t, part[2], plen[2], idx[2], P->nvn, "normal", vn)) != BSP_OK)
        return st;
    *form = (have[1] ? REF_VT : 0) | (have[2] ? REF_VN : 0);
    return BSP_OK;
malformed:
    return fail(P, BSP_ERR_PARSE, t->line,
                "malformed vertex reference %s in 'f' statement (expected v, v/vt, v//vn or "
                "v/vt/vn)",
                mesh_show_token(t->s, t->len, shown, sizeof shown));
}

static const char *form_name(int form)
{
    static const char *const names[4] = {"v", "v/vt", "v//vn", "v/vt/vn"};
    return names[form & 3];
}

/* An 'f' statement; its keyword (on line KLINE) is consumed. */
static bsp_status read_face(obj_parser *P, size_t kline)
{
    token t, first = {NULL, 0, 0};
    size_t n = 0;
    int form0 = 0;
    bsp_status st;
    char shown[MESH_SHOW_SIZE], shown0[MESH_SHOW_SIZE];
    while (next_token(P, &t)) {
        if (n >= SCENE_MAX_POLY_VERTS)
            return fail(P, BSP_ERR_LIMIT, kline, "face with more than %zu vertices",
                        SCENE_MAX_POLY_VERTS);
        if (n == P->cap_f) {
            size_t ncap = P->cap_f ? P->cap_f * 2 : 16;
            bsp_vec3 *a = realloc(P->fv, ncap * sizeof *a);
            if (!a)
                return fail(P, BSP_ERR_NOMEM, kline, "out of memory");
            P->fv = a;
            bsp_vec3 *b = realloc(P->fn, ncap * sizeof *b);
            if (!b)
                return fail(P, BSP_ERR_NOMEM, kline, "out of memory");
            P->fn = b;
            P->cap_f = ncap;
        }
        size_t v = 0, vn = SIZE_MAX;
        int form = 0;
        if ((st = read_ref(P, &t, &v, &vn, &form)) != BSP_OK)
            return st;
        if (n == 0) {
            first = t;
            form0 = form;
        } else if ((form ^ form0) & REF_VN) {
            return fail(P, BSP_ERR_PARSE, t.line,
                        "face mixes corners with and without normals: %s (%s) and %s (%s)",
                        mesh_show_token(first.s, first.len, shown0, sizeof shown0),
                        form_name(form0), mesh_show_token(t.s, t.len, shown, sizeof shown),
                        form_name(form));
        }
        P->fv[n] = P->v[v];
        if (vn != SIZE_MAX)
            P->fn[n] = P->vn[vn];
        n++;
    }
    if (n < 3)
        return fail(P, BSP_ERR_PARSE, kline, "face with %zu vertices (at least 3 are needed)", n);
    scene_set_source(P->scene, P->name, kline);
    if (form0 & REF_VN)
        return bsp_scene_add_patch(P->scene, P->fv, P->fn, n, P->err);
    return bsp_scene_add_polygon(P->scene, P->fv, n, P->err);
}

/* One statement whose keyword K has been read. */
static bsp_status read_statement(obj_parser *P, const token *k)
{
    double x[7];
    size_t n = 0; /* set by read_values; initialised for gcc -O3's maybe-uninitialized */
    bsp_status st;
    char shown[MESH_SHOW_SIZE];
    const size_t kl = k->line;
    switch (k->len) {
    case 1:
        switch (k->s[0]) {
        case 'v':
            if ((st = read_values(P, "v", kl, x, 3, 6, &n)) != BSP_OK)
                return st;
            if (n == 5)
                return fail(P, BSP_ERR_PARSE, kl,
                            "'v' statement with 5 numbers (expected x y z [w] or x y z r g b)");
            return push_vec(P, &P->v, &P->nv, &P->cap_v, bsp_v3(x[0], x[1], x[2]), "vertices",
                            kl);
        case 'f':
            return read_face(P, kl);
        case 'g':
        case 'o':
        case 's':
            return BSP_OK;
        }
        break;
    case 2:
        if (token_is(k, "vn")) {
            if ((st = read_values(P, "vn", kl, x, 3, 3, &n)) != BSP_OK)
                return st;
            return push_vec(P, &P->vn, &P->nvn, &P->cap_vn, bsp_v3(x[0], x[1], x[2]), "normals",
                            kl);
        }
        if (token_is(k, "vt")) {
            if ((st = read_values(P, "vt", kl, x, 1, 3, &n)) != BSP_OK)
                return st;
            if (P->nvt >= MESH_MAX_VERTS)
                return fail(P, BSP_ERR_LIMIT, kl, "more than %zu texture coordinates",
                            MESH_MAX_VERTS);
            P->nvt++;
            return BSP_OK;
        }
        break;
    default:
        if (token_is(k, "usemtl") || token_is(k, "mtllib"))
            return BSP_OK;
        break;
    }
    for (size_t i = 0; i < OBJ_UNSUPPORTED; i++)
        if (token_is(k, obj_unsupported[i].kw)) {
            if (P->ignored[i]++ == 0)
                P->ignored_line[i] = kl;
            return BSP_OK;
        }
    mesh_show_token(k->s, k->len, shown, sizeof shown);
    if (is_digit(k->s[0]) || k->s[0] == '-' || k->s[0] == '+' || k->s[0] == '.')
        return fail(P, BSP_ERR_PARSE, kl,
                    "unexpected number %s where a statement keyword was expected", shown);
    return fail(P, BSP_ERR_PARSE, kl, "unknown statement %s", shown);
}

static bsp_status parse_obj(const char *buf, size_t len, const char *name, bsp_scene **out,
                            bsp_error *err)
{
    obj_parser P;
    memset(&P, 0, sizeof P);
    P.name = name;
    P.p = buf;
    P.end = buf + len;
    P.line = 1;
    P.err = err;
    P.scene = mesh_scene_create();
    if (!P.scene)
        return error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory");
    bsp_status st = BSP_OK;
    while (P.p < P.end) {
        token k;
        if (next_token(&P, &k) && (st = read_statement(&P, &k)) != BSP_OK)
            break;
        end_statement(&P);
    }
    free(P.v);
    free(P.vn);
    free(P.fv);
    free(P.fn);
    if (st == BSP_OK) {
        for (size_t i = 0; i < OBJ_UNSUPPORTED; i++)
            if (P.ignored[i])
                scene_warn(P.scene, "%s:%zu: ignored %zu '%s' statement%s: %s (first here)", name,
                           P.ignored_line[i], P.ignored[i], obj_unsupported[i].kw,
                           P.ignored[i] == 1 ? "" : "s", obj_unsupported[i].why);
        st = mesh_finish(P.scene, name, err);
    }
    if (st != BSP_OK) {
        bsp_scene_destroy(P.scene);
        return st;
    }
    *out = P.scene;
    return BSP_OK;
}

/* parse_obj on plain or gzip input. */
static bsp_status parse_obj_any(const char *buf, size_t len, const char *name, bsp_scene **out,
                                bsp_error *err)
{
    return scene_parse_maybe_gzip(parse_obj, buf, len, name, MESH_MAX_INPUT, 0, out, err);
}

bsp_status obj_load_memory(const char *buf, size_t len, const char *name, bsp_scene **out,
                           bsp_error *err)
{
    return mesh_load_memory(parse_obj_any, buf, len, name, out, err);
}

bsp_status obj_load_file(const char *path, bsp_scene **out, bsp_error *err)
{
    return mesh_load_file(parse_obj_any, path, out, err);
}
