/*
 * kd_file.c — a built kd-tree as a file: bsp_accel_save and bsp_accel_load
 * (accel.h; the format in docs/formats.md, "kd-tree files").
 *
 * Layout, every number little-endian whatever the machine:
 *
 *   header (KD_FILE_HEADER bytes): magic "BSPRAYKD", format version, the
 *     method and the options that shaped the tree (limits, mailboxes, the
 *     resolved cost model), the scene's primitive count and fingerprint,
 *     the tree's padding and root box, its leaf-budget figures, the build's
 *     seconds, the node and reference counts;
 *   nodes: two 32-bit words each, as in memory (kd_tree.h);
 *   references: one 32-bit primitive index each;
 *   CRC-32 (zlib's) of everything before it.
 *
 * The loader trusts nothing in the file: the counts must account for its
 * size exactly (so a damaged count cannot ask for absurd memory), the
 * checksum must match, and the structure is checked whole by one walk from
 * the root (check_structure) before the traversal's copies are made from
 * it: no index, count or plane in the file can make a query read out of
 * bounds, recurse past the traversal's stack or loop.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "accel/kd_cost.h"
#include "accel/kd_tree.h"
#include "util/errno_text.h"

#define KD_FILE_MAGIC "BSPRAYKD"
#define KD_FILE_VERSION 1u
/* magic 8; 8 words of 4; 22 doubles (6 costs, empty bonus, least saving,
 * padding, root box 6, budget cut, build seconds, 5 reserved); 4 counts of 8 */
#define KD_FILE_HEADER (8 + 8 * 4 + 22 * 8 + 4 * 8)
#define KD_FILE_CHUNK 4096 /* nodes or references converted at a time */

/* --- little-endian fields ----------------------------------------------------------------- */

static void put_u32(unsigned char *p, uint32_t x)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(x >> (8 * i));
}

static void put_u64(unsigned char *p, uint64_t x)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(x >> (8 * i));
}

static void put_f64(unsigned char *p, double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    put_u64(p, u);
}

static uint32_t get_u32(const unsigned char *p)
{
    uint32_t x = 0;
    for (int i = 0; i < 4; i++)
        x |= (uint32_t)p[i] << (8 * i);
    return x;
}

static uint64_t get_u64(const unsigned char *p)
{
    uint64_t x = 0;
    for (int i = 0; i < 8; i++)
        x |= (uint64_t)p[i] << (8 * i);
    return x;
}

static double get_f64(const unsigned char *p)
{
    uint64_t u = get_u64(p);
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* --- the scene's fingerprint -------------------------------------------------------------- */

static uint64_t fnv_u64(uint64_t h, uint64_t x)
{
    for (int i = 0; i < 8; i++) {
        h ^= (x >> (8 * i)) & 0xff;
        h *= 1099511628211ull;
    }
    return h;
}

static uint64_t fnv_f64(uint64_t h, double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return fnv_u64(h, u);
}

static uint64_t fnv_vec(uint64_t h, bsp_vec3 v)
{
    return fnv_f64(fnv_f64(fnv_f64(h, v.x), v.y), v.z);
}

/* FNV-1a over every primitive's kind and the numbers of its surface, as
 * the scene reads them back (bsp_scene_prim_sphere, _cone, _vertex): two
 * scenes with the same fingerprint have the same primitives in the same
 * order, to the bit. With ROUNDED_TRIANGLES, a triangle's second and third
 * vertices as bspray 0.2.0 and older read them back, v0 + (v - v0) rounded
 * (they kept v0 and the edges): what those versions wrote in their files,
 * so that such a file is named for what it is (bspray_kd_load). */
static uint64_t scene_fingerprint_of(const bsp_scene *s, int rounded_triangles)
{
    uint64_t h = 14695981039346656037ull;
    size_t n = bsp_scene_prim_count(s);
    for (size_t p = 0; p < n; p++) {
        bsp_prim_kind kind = bsp_scene_prim_kind(s, p);
        h = fnv_u64(h, (uint64_t)kind);
        bsp_vec3 a, b;
        double ra, rb;
        switch (kind) {
        case BSP_PRIM_SPHERE:
            if (bsp_scene_prim_sphere(s, p, &a, &ra) == BSP_OK)
                h = fnv_f64(fnv_vec(h, a), ra);
            break;
        case BSP_PRIM_CONE:
            if (bsp_scene_prim_cone(s, p, &a, &ra, &b, &rb) == BSP_OK)
                h = fnv_f64(fnv_vec(fnv_f64(fnv_vec(h, a), ra), b), rb);
            break;
        case BSP_PRIM_POLYGON:
        case BSP_PRIM_PATCH: {
            size_t nv = bsp_scene_prim_vertex_count(s, p);
            h = fnv_u64(h, (uint64_t)nv);
            bsp_vec3 v0 = {{0.0, 0.0, 0.0}};
            for (size_t i = 0; i < nv; i++)
                if (bsp_scene_prim_vertex(s, p, i, &a) == BSP_OK) {
                    if (i == 0)
                        v0 = a;
                    else if (rounded_triangles && s->prims[p].shape == SHAPE_TRIANGLE)
                        a = bsp_v3(v0.x + (a.x - v0.x), v0.y + (a.y - v0.y), v0.z + (a.z - v0.z));
                    h = fnv_vec(h, a);
                }
            break;
        }
        default:
            break;
        }
    }
    return h;
}

static uint64_t scene_fingerprint(const bsp_scene *s)
{
    return scene_fingerprint_of(s, 0);
}

/* --- saving ------------------------------------------------------------------------------- */

typedef struct writer {
    FILE *f;
    uLong crc;
    int failed;
} writer;

static void write_bytes(writer *w, const unsigned char *p, size_t n)
{
    if (w->failed || n == 0)
        return;
    w->crc = crc32(w->crc, p, (uInt)n);
    if (fwrite(p, 1, n, w->f) != n)
        w->failed = 1;
}

/* The header of tree T of A (the options resolved as the build used them). */
static void make_header(const bsp_accel *a, const kd_tree *t, unsigned char *h)
{
    kd_cost_model m;
    kd_cost_resolve(&a->opts, &m);
    unsigned char *p = h;
    memcpy(p, KD_FILE_MAGIC, 8);
    p += 8;
    const uint32_t words[8] = {KD_FILE_VERSION,
                               (uint32_t)a->opts.kind,
                               (uint32_t)(a->opts.mailbox != 0),
                               (uint32_t)t->max_depth,
                               (uint32_t)t->max_leaf_prims,
                               (uint32_t)(a->opts.sah_straddle_twice != 0),
                               (uint32_t)(a->opts.sah_split_to_limits != 0),
                               (uint32_t)t->budget_rebuilt};
    for (int i = 0; i < 8; i++, p += 4)
        put_u32(p, words[i]);
    const double reals[22] = {m.c.traversal,      m.c.sphere, m.c.triangle,    m.c.polygon_base,
                              m.c.polygon_vertex, m.c.cone,   m.empty_bonus,   m.min_saving,
                              t->pad,             t->box.lo.x, t->box.lo.y,    t->box.lo.z,
                              t->box.hi.x,        t->box.hi.y, t->box.hi.z,    t->budget_cut,
                              a->build_seconds,   0.0,         0.0,            0.0,
                              0.0,                0.0};
    for (int i = 0; i < 22; i++, p += 8)
        put_f64(p, reals[i]);
    const uint64_t counts[4] = {(uint64_t)bsp_scene_prim_count(a->scene),
                                scene_fingerprint(a->scene), (uint64_t)t->nnodes,
                                (uint64_t)t->nprims};
    for (int i = 0; i < 4; i++, p += 8)
        put_u64(p, counts[i]);
}

bsp_status bsp_accel_save(const bsp_accel *a, const char *path, bsp_error *err)
{
    if (a->opts.kind == BSP_ACCEL_NAIVE || !a->impl)
        return error_set(err, BSP_ERR_INVALID, path, 0,
                         "the naive method has no structure to save");
    if (a->opts.kind == BSP_ACCEL_GRID || a->opts.kind == BSP_ACCEL_OCTREE ||
        accel_is_bvh(a->opts.kind))
        return error_set(err, BSP_ERR_INVALID, path, 0,
                         "only the kd-trees of kaplan and the sah family are saved; this %s "
                         "is rebuilt instead (it builds in about the time a load takes)",
                         bsp_accel_kind_name(a->opts.kind));
    const kd_tree *t = a->impl;
    size_t plen = strlen(path);
    char *part = malloc(plen + 32);
    if (!part)
        return error_set(err, BSP_ERR_NOMEM, path, 0, "out of memory");
    snprintf(part, plen + 32, "%s.part%ld", path, (long)getpid());
    /* A new or regular file is written beside PATH and renamed over it, so
     * that a failed save leaves no half file. Anything else (a device such as
     * /dev/null, a pipe, a symbolic link) is written where it is: renaming
     * over it would replace it with a file. */
    struct stat ps;
    const int in_place = lstat(path, &ps) == 0 && !S_ISREG(ps.st_mode);
    writer w = {fopen(in_place ? path : part, "wb"), crc32(0L, Z_NULL, 0), 0};
    if (!w.f) {
        bsp_status st = error_set(err, BSP_ERR_IO, path, 0, "cannot write: %s", ERRNO_TEXT(errno));
        free(part);
        return st;
    }
    unsigned char header[KD_FILE_HEADER];
    make_header(a, t, header);
    write_bytes(&w, header, sizeof header);
    unsigned char buf[KD_FILE_CHUNK * 8];
    for (uint32_t i = 0; i < t->nnodes && !w.failed;) {
        size_t k = 0;
        for (; k < KD_FILE_CHUNK && i < t->nnodes; k++, i++) {
            uint32_t word;
            memcpy(&word, &t->nodes[i].u, sizeof word); /* the split's bits or the first entry */
            put_u32(buf + 8 * k, t->nodes[i].bits);
            put_u32(buf + 8 * k + 4, word);
        }
        write_bytes(&w, buf, 8 * k);
    }
    for (size_t i = 0; i < t->nprims && !w.failed;) {
        size_t k = 0;
        for (; k < 2 * KD_FILE_CHUNK && i < t->nprims; k++, i++)
            put_u32(buf + 4 * k, t->prims[i]);
        write_bytes(&w, buf, 4 * k);
    }
    unsigned char crc[4];
    put_u32(crc, (uint32_t)w.crc);
    if (!w.failed && fwrite(crc, 1, 4, w.f) != 4)
        w.failed = 1;
    int saved_errno = errno;
    if (fclose(w.f) != 0 && !w.failed) {
        w.failed = 1;
        saved_errno = errno;
    }
    if (!w.failed && !in_place && rename(part, path) != 0) {
        w.failed = 1;
        saved_errno = errno;
    }
    bsp_status st = BSP_OK;
    if (w.failed) {
        if (!in_place)
            remove(part);
        st = error_set(err, BSP_ERR_IO, path, 0, "cannot write: %s", ERRNO_TEXT(saved_errno));
    }
    free(part);
    return st;
}

/* --- loading ------------------------------------------------------------------------------ */

/* What the header says, checked field by field against SCENE. */
typedef struct file_header {
    uint32_t version, kind, mailbox, max_depth, max_leaf, straddle_twice, split_to_limits,
        budget_rebuilt;
    double costs[6], empty_bonus, min_saving, pad, box[6], budget_cut, build_seconds;
    uint64_t nprims_scene, fingerprint, nnodes, nrefs;
} file_header;

static void read_header(const unsigned char *h, file_header *fh)
{
    const unsigned char *p = h + 8;
    uint32_t *words[8] = {&fh->version,  &fh->kind,           &fh->mailbox,
                          &fh->max_depth, &fh->max_leaf,      &fh->straddle_twice,
                          &fh->split_to_limits, &fh->budget_rebuilt};
    for (int i = 0; i < 8; i++, p += 4)
        *words[i] = get_u32(p);
    double reals[22];
    for (int i = 0; i < 22; i++, p += 8)
        reals[i] = get_f64(p);
    memcpy(fh->costs, reals, sizeof fh->costs);
    fh->empty_bonus = reals[6];
    fh->min_saving = reals[7];
    fh->pad = reals[8];
    memcpy(fh->box, reals + 9, sizeof fh->box);
    fh->budget_cut = reals[15];
    fh->build_seconds = reals[16];
    uint64_t *counts[4] = {&fh->nprims_scene, &fh->fingerprint, &fh->nnodes, &fh->nrefs};
    for (int i = 0; i < 4; i++, p += 8)
        *counts[i] = get_u64(p);
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Checks the loaded tree T over SCENE by one walk from the root, with the
 * cells on a stack (its depth bounded by T's limit, at most
 * BSP_KD_MAX_DEPTH_LIMIT): every interior node's children inside the array
 * and after it, depths within the limit, split planes finite and inside
 * their cells, no stray flag bit, leaf ranges inside the reference array;
 * every node reached exactly once (so the nodes form one tree); every
 * reference a live primitive of SCENE. SEEN: scratch of T's node count. */
static bsp_status check_structure(const kd_tree *t, const bsp_scene *scene, uint8_t *seen,
                                  const char *path, bsp_error *err)
{
    struct pending {
        uint32_t node;
        int depth;
        bsp_box cell;
    } stack[BSP_KD_MAX_DEPTH_LIMIT + 2];
    size_t top = 0, reached = 0;
    memset(seen, 0, t->nnodes);
    stack[top++] = (struct pending){0, 0, t->box};
    while (top > 0) {
        const struct pending at = stack[--top];
        const uint32_t i = at.node;
        const kd_node *n = &t->nodes[i];
        if (seen[i])
            return error_set(err, BSP_ERR_PARSE, path, 0,
                             "damaged: node %u is the child of two nodes", i);
        seen[i] = 1;
        reached++;
        if (n->bits & 4u)
            return error_set(err, BSP_ERR_PARSE, path, 0, "damaged: node %u has a stray flag", i);
        if (kd_is_leaf(n)) {
            uint64_t first = n->u.first, count = kd_count(n);
            if (first + count > t->nprims)
                return error_set(err, BSP_ERR_PARSE, path, 0,
                                 "damaged: leaf %u lists references %llu..%llu of %zu", i,
                                 (unsigned long long)first,
                                 (unsigned long long)(first + count), t->nprims);
            continue;
        }
        uint32_t child = kd_child(n);
        if (child <= i || child >= t->nnodes - 1)
            return error_set(err, BSP_ERR_PARSE, path, 0,
                             "damaged: node %u has children %u and %u of %u nodes", i, child,
                             child + 1, t->nnodes);
        if (at.depth + 1 > t->max_depth)
            return error_set(err, BSP_ERR_PARSE, path, 0,
                             "damaged: node %u's children lie deeper than the limit %d", i,
                             t->max_depth);
        unsigned axis = kd_axis(n);
        double s = (double)n->u.split;
        if (!(s >= at.cell.lo.v[axis] && s <= at.cell.hi.v[axis]))
            return error_set(err, BSP_ERR_PARSE, path, 0,
                             "damaged: node %u splits outside its cell", i);
        /* the right child waits below the left one: the stack holds at most
         * one waiting node per level, and the depth is bounded above */
        stack[top] = stack[top + 1] = (struct pending){child + 1, at.depth + 1, at.cell};
        stack[top].cell.lo.v[axis] = s;
        stack[top + 1].node = child;
        stack[top + 1].cell.hi.v[axis] = s;
        top += 2;
    }
    if (reached != t->nnodes)
        return error_set(err, BSP_ERR_PARSE, path, 0,
                         "damaged: %zu of its %u nodes are not in the tree", t->nnodes - reached,
                         t->nnodes);
    const size_t np = bsp_scene_prim_count(scene);
    for (size_t k = 0; k < t->nprims; k++) {
        uint32_t p = t->prims[k];
        if (p >= np || bsp_scene_prim_kind(scene, p) == BSP_PRIM_DROPPED)
            return error_set(err, BSP_ERR_PARSE, path, 0,
                             "damaged: reference %zu names primitive %u, which this scene %s", k,
                             p, p >= np ? "does not have" : "dropped");
    }
    return BSP_OK;
}

/* Reads N bytes at P from F, adding them to *CRC; 0 on a short read. */
static int read_bytes(FILE *f, unsigned char *p, size_t n, uLong *crc)
{
    if (fread(p, 1, n, f) != n)
        return 0;
    *crc = crc32(*crc, p, (uInt)n);
    return 1;
}

/* The tree of the file F (SIZE bytes) under the header FH, read into T (set
 * up by kd_tree_init over the scene) and checked. */
static bsp_status read_tree(FILE *f, const file_header *fh, uLong crc, kd_tree *t,
                            const bsp_scene *scene, const char *path, bsp_error *err)
{
    t->nnodes = (uint32_t)fh->nnodes;
    t->nprims = (size_t)fh->nrefs;
    kd_node *nodes = realloc(t->nodes, (size_t)fh->nnodes * sizeof *nodes);
    if (!nodes)
        return error_set(err, BSP_ERR_NOMEM, path, 0, "out of memory");
    t->nodes = nodes;
    t->cap_nodes = t->nnodes;
    t->prims = malloc((fh->nrefs ? (size_t)fh->nrefs : 1) * sizeof *t->prims);
    if (!t->prims)
        return error_set(err, BSP_ERR_NOMEM, path, 0, "out of memory");
    t->cap_prims = t->nprims;
    unsigned char buf[KD_FILE_CHUNK * 8];
    for (uint32_t i = 0; i < t->nnodes;) {
        size_t k = t->nnodes - i < KD_FILE_CHUNK ? t->nnodes - i : KD_FILE_CHUNK;
        if (!read_bytes(f, buf, 8 * k, &crc))
            return error_set(err, BSP_ERR_PARSE, path, 0, "truncated");
        for (size_t j = 0; j < k; j++, i++) {
            uint32_t word = get_u32(buf + 8 * j + 4);
            t->nodes[i].bits = get_u32(buf + 8 * j);
            memcpy(&t->nodes[i].u, &word, sizeof word);
        }
    }
    for (size_t i = 0; i < t->nprims;) {
        size_t k = t->nprims - i < 2 * KD_FILE_CHUNK ? t->nprims - i : 2 * KD_FILE_CHUNK;
        if (!read_bytes(f, buf, 4 * k, &crc))
            return error_set(err, BSP_ERR_PARSE, path, 0, "truncated");
        for (size_t j = 0; j < k; j++, i++)
            t->prims[i] = get_u32(buf + 4 * j);
    }
    unsigned char tail[4];
    if (fread(tail, 1, 4, f) != 4)
        return error_set(err, BSP_ERR_PARSE, path, 0, "truncated");
    if (get_u32(tail) != (uint32_t)crc)
        return error_set(err, BSP_ERR_PARSE, path, 0,
                         "damaged: its checksum does not match its contents");
    uint8_t *seen = malloc(t->nnodes);
    bsp_status st = seen ? check_structure(t, scene, seen, path, err)
                         : error_set(err, BSP_ERR_NOMEM, path, 0, "out of memory");
    free(seen);
    return st;
}

/* The options of the tree FH describes: the defaults with its method,
 * limits and resolved cost model (a resolved 0 stored as "none"). */
static void header_options(const file_header *fh, bsp_build_options *o)
{
    bsp_build_options_defaults(o);
    o->kind = (bsp_accel_kind)fh->kind;
    o->mailbox = (int)fh->mailbox;
    o->max_depth = (int)fh->max_depth;
    o->max_leaf_prims = (int)fh->max_leaf;
    o->sah_straddle_twice = (int)fh->straddle_twice;
    o->sah_split_to_limits = (int)fh->split_to_limits;
    o->sah_costs.traversal = fh->costs[0];
    o->sah_costs.sphere = fh->costs[1];
    o->sah_costs.triangle = fh->costs[2];
    o->sah_costs.polygon_base = fh->costs[3];
    o->sah_costs.polygon_vertex = fh->costs[4];
    o->sah_costs.cone = fh->costs[5];
    o->sah_empty_bonus = fh->empty_bonus > 0.0 ? fh->empty_bonus : -1.0;
    o->sah_min_saving = fh->min_saving > 0.0 ? fh->min_saving : -1.0;
}

/* Whether the header's options are ones a build can have made. */
static int header_options_valid(const file_header *fh)
{
    if (fh->kind < BSP_ACCEL_KAPLAN || fh->kind > BSP_ACCEL_SAH_MIXED)
        return 0;
    if (fh->mailbox > 1 || fh->straddle_twice > 1 || fh->split_to_limits > 1 ||
        fh->budget_rebuilt > 1)
        return 0;
    if (fh->max_depth < 1 || fh->max_depth > BSP_KD_MAX_DEPTH_LIMIT || fh->max_leaf < 1 ||
        fh->max_leaf > (uint32_t)1 << 30)
        return 0;
    for (int i = 0; i < 6; i++)
        if (!(fh->costs[i] > 0.0 && isfinite(fh->costs[i])))
            return 0;
    return fh->empty_bonus >= 0.0 && fh->empty_bonus < 1.0 && fh->min_saving >= 0.0 &&
           isfinite(fh->min_saving) && !isnan(fh->budget_cut) && fh->build_seconds >= 0.0 &&
           isfinite(fh->build_seconds);
}

bsp_status bsp_accel_load(const bsp_scene *scene, const char *path, bsp_accel **out,
                          bsp_error *err)
{
    *out = NULL;
    double t0 = accel_now();
    FILE *f = fopen(path, "rb");
    if (!f)
        return error_set(err, BSP_ERR_IO, path, 0, "cannot open: %s", ERRNO_TEXT(errno));
    struct stat fs;
    if (fstat(fileno(f), &fs) != 0 || !S_ISREG(fs.st_mode)) {
        fclose(f);
        return error_set(err, BSP_ERR_IO, path, 0, "cannot read: not a regular file");
    }
    const long size = (long)fs.st_size;
    unsigned char h[KD_FILE_HEADER];
    uLong crc = crc32(0L, Z_NULL, 0);
    if ((size_t)size < sizeof h + 4 || !read_bytes(f, h, sizeof h, &crc) ||
        memcmp(h, KD_FILE_MAGIC, 8) != 0) {
        fclose(f);
        return error_set(err, BSP_ERR_PARSE, path, 0,
                         "not a bspray kd-tree file (bspray build writes them)");
    }
    file_header fh;
    read_header(h, &fh);
    bsp_status st = BSP_OK;
    const uint64_t fingerprint = scene_fingerprint(scene); /* a pass over the scene: once */
    /* the counts must account for the file's size exactly; each is first
     * bounded so that the sum cannot overflow */
    uint64_t want = fh.nnodes < KD_MAX_NODES && fh.nrefs <= UINT32_MAX
                        ? (uint64_t)sizeof h + 8 * fh.nnodes + 4 * fh.nrefs + 4
                        : 0;
    if (fh.version != KD_FILE_VERSION)
        st = error_set(err, BSP_ERR_PARSE, path, 0,
                       "kd-tree file format version %u; this bspray reads version %u",
                       fh.version, KD_FILE_VERSION);
    else if (fh.nnodes == 0 || want != (uint64_t)size)
        st = error_set(err, BSP_ERR_PARSE, path, 0,
                       "damaged: %ld bytes, but its header counts %llu nodes and %llu references",
                       size, (unsigned long long)fh.nnodes, (unsigned long long)fh.nrefs);
    else if (!header_options_valid(&fh))
        st = error_set(err, BSP_ERR_PARSE, path, 0, "damaged: its build options are invalid");
    else if (fh.nprims_scene == (uint64_t)bsp_scene_prim_count(scene) &&
             fh.fingerprint != fingerprint && fh.fingerprint == scene_fingerprint_of(scene, 1))
        st = error_set(err, BSP_ERR_INVALID, path, 0,
                       "was saved for this scene by bspray 0.2.0 or older, which read its "
                       "triangles' vertices rounded (v0 + (v1 - v0)); this version keeps them "
                       "exact, and its trees differ: build the tree again");
    else if (fh.nprims_scene != (uint64_t)bsp_scene_prim_count(scene) ||
             fh.fingerprint != fingerprint)
        st = error_set(err, BSP_ERR_INVALID, path, 0,
                       "was saved for another scene (%llu primitives, fingerprint %016llx); "
                       "this one has %zu primitives, fingerprint %016llx",
                       (unsigned long long)fh.nprims_scene, (unsigned long long)fh.fingerprint,
                       bsp_scene_prim_count(scene), (unsigned long long)fingerprint);
    if (st != BSP_OK) {
        fclose(f);
        return st;
    }
    bsp_accel *a = calloc(1, sizeof *a);
    kd_tree *t = calloc(1, sizeof *t); /* zeroed: kd_tree_free is safe before kd_tree_init */
    if (!a || !t || !kd_tree_init(t, scene, (int)fh.max_depth, (int)fh.max_leaf)) {
        if (t)
            kd_tree_free(t);
        free(t);
        free(a);
        fclose(f);
        return error_set(err, BSP_ERR_NOMEM, path, 0, "out of memory");
    }
    /* the same scene gives the same padding and root box, to the bit */
    const double box[6] = {t->box.lo.x, t->box.lo.y, t->box.lo.z,
                           t->box.hi.x, t->box.hi.y, t->box.hi.z};
    int same = same_bits(fh.pad, t->pad);
    for (int k = 0; k < 6; k++)
        same &= same_bits(fh.box[k], box[k]);
    if (!same)
        st = error_set(err, BSP_ERR_INVALID, path, 0,
                       "its root cell or padding differs from this scene's (saved by another "
                       "version of bspray?)");
    else
        st = read_tree(f, &fh, crc, t, scene, path, err);
    fclose(f);
    if (st != BSP_OK) {
        kd_tree_free(t);
        free(t);
        free(a);
        return st;
    }
    t->budget_cut = fh.budget_cut;
    t->budget_rebuilt = (int)fh.budget_rebuilt;
    a->scene = scene;
    header_options(&fh, &a->opts);
    st = kd_accel_adopt(a, t, err); /* frees T when it fails */
    if (st != BSP_OK) {
        free(a);
        return st;
    }
    a->build_seconds = accel_now() - t0;
    *out = a;
    return BSP_OK;
}
