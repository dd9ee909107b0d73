/*
 * bvh_wide_traverse.c — closest-hit and any-hit queries on the wide BVHs
 * (bvh.h, width W = 4 or 8). At a wide node the ray's interval is clipped
 * to its W boxes, four at a time; of the boxes met, the nearest is entered
 * (a leaf is tested) and the others are pushed with their entry t,
 * farthest first. A popped node is skipped when its entry lies beyond the
 * best hit found since: the entry computed is at most the t of any hit
 * below it, so the skip loses no hit, ties included. Each width has a walk
 * of its own (walk_wide with W a constant: the lanes' loops have fixed
 * bounds, and the compiler sizes each walk's arrays and offsets).
 *
 * Float tests (SSE, four lanes) serve the rays whose origin lies within
 * t->float_origin on every axis (bvh.h: there a computed slab t is the
 * exact t of a face moved by at most about a quarter of the pad, and hits
 * lie 3/4 pad inside every box above them). Their direction is scaled by a
 * power of two, 2^-shift, to a largest component in [1, 2): exact, so the
 * scaled parameter t' = t 2^shift is exact too, and every t' a hit can
 * have is far inside the float range. The ray's [tmin, best t] enters the
 * tests as floats rounded outward. Other rays of the precision domain (and
 * every ray where SSE is missing) take the same walk with double tests, as
 * exact as the two-wide tree's; rays outside the domain, the naive loop.
 *
 * A box's near face on axis k is its low one when 1 / d_k >= 0 (d_k = +0
 * included), else its high one: (near - o) / d_k <= (far - o) / d_k then,
 * so no min or max is needed. A zero component gives +-inf, or NaN where the
 * origin lies exactly on a face, where the ray's line cannot hold an
 * accepted hit of the box (either answer is safe); an unused lane's box,
 * +inf..-inf, always misses (entry +inf, exit -inf). Entries on the stack
 * are floats rounded down (in t' units on the float path, t on the double
 * one), compared with the best t rounded up.
 *
 * Counters: N_TS counts box tests, W per wide node (unused lanes included)
 * and one for the root, as the two-wide tree counts two per pair; N_ETS the
 * leaves entered; N_IT the primitives tested.
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "accel/bvh.h"
#include "accel/bvh_query.h"

/* 2^E as a double, for E in [-1022, 1023]. */
static inline double pow2(int e)
{
    uint64_t u = (uint64_t)(e + 1023) << 52;
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

typedef struct wide_ray {
    double o[3], inv[3]; /* the double tests' (t units) */
    unsigned near[3], far[3]; /* per axis, byte offsets in a wide node of the near, far faces */
    double scale;        /* the float tests' t' = t scale, scale = 2^shift (1: double tests) */
#if defined(__SSE2__)
    __m128 of[3], invf[3]; /* the float tests' origin and scaled 1 / d */
#endif
} wide_ray;

/* T in the walk's units (t' = t SCALE, exact but where it underflows),
 * rounded down / up to a float; a positive t never rounds up to 0. */
static inline float t_down(double t, double scale)
{
    return bvh_float_down(t * scale);
}
static inline float t_up(double t, double scale)
{
    float f = bvh_float_up(t * scale);
    return f == 0.0f && t > 0.0 ? FLT_TRUE_MIN : f;
}

/* Prepares R's double tests for RAY and says whether RAY's [tmin, tmax]
 * meets T's root box (near and far faces as in the wide nodes'): the rays that
 * miss it, half of a camera's on the dragon, pay nothing more. */
static inline __attribute__((always_inline)) int wide_ray_root(wide_ray *r, const bvh *t,
                                                                const bsp_ray *ray)
{
    const double *o = ray->org.v, *d = ray->dir.v;
    double a0 = ray->tmin, a1 = ray->tmax;
    for (unsigned k = 0; k < 3; k++) {
        r->o[k] = o[k];
        r->inv[k] = 1.0 / d[k];
        const unsigned lo = 4 * k * t->width, hi = 4 * (3 + k) * t->width; /* bvh.h */
        const int neg = signbit(r->inv[k]);
        r->near[k] = neg ? hi : lo;
        r->far[k] = neg ? lo : hi;
        double a = ((double)(neg ? t->root.hi[k] : t->root.lo[k]) - o[k]) * r->inv[k];
        double b = ((double)(neg ? t->root.lo[k] : t->root.hi[k]) - o[k]) * r->inv[k];
        a0 = a > a0 ? a : a0;
        a1 = b < a1 ? b : a1;
    }
    r->scale = 1.0;
    return a0 <= a1;
}

/* Prepares R's float tests for RAY when they may serve it (then 1). */
static int wide_ray_float(wide_ray *r, const bvh *t, const bsp_ray *ray)
{
    const double *o = ray->org.v, *d = ray->dir.v;
    double m = 0.0;
    int fl = 1;
    for (unsigned k = 0; k < 3; k++) {
        const double a = fabs(d[k]);
        m = a > m ? a : m; /* fmax is a libm call here */
        fl &= fabs(o[k]) <= t->float_origin;
    }
#if defined(__SSE2__)
    if (!fl)
        return 0;
    /* m = 2^shift x [1, 2) (m >= 1e-100 in the domain: a normal double),
     * so d 2^-shift has its largest component in [1, 2) and t' = t 2^shift */
    uint64_t bits;
    memcpy(&bits, &m, sizeof bits);
    r->scale = pow2((int)((bits >> 52) & 0x7ff) - 1023);
    for (unsigned k = 0; k < 3; k++) {
        r->of[k] = _mm_set1_ps((float)o[k]);
        /* 1 / (d 2^-shift) rounded to float; +-inf for +-0 */
        r->invf[k] = _mm_set1_ps((float)(r->inv[k] * r->scale));
    }
    return 1;
#else
    (void)m;
    (void)fl;
    return 0;
#endif
}

/* The ray's float tests' values, in locals of the walk (wide_ray's are
 * __m128, which may alias any store, so the compiler would load them again
 * after every store of the loop). */
typedef struct float_slabs {
#if defined(__SSE2__)
    __m128 of0, of1, of2, invf0, invf1, invf2;
#endif
    unsigned near0, near1, near2, far0, far1, far2;
} float_slabs;

/* Which of wide node Q's W boxes R's interval [T0, T1] (walk units) meets,
 * as a bit mask; E[c] is where it enters box c. The float tests take F. */
static inline __attribute__((always_inline)) unsigned
wide_hit(const unsigned char *q, unsigned w, const wide_ray *r, const float_slabs *f,
         double t0, double t1, float t0f, float t1f, float e[BVH_WIDEST], int use_float)
{
#if defined(__SSE2__)
    if (use_float) {
        unsigned mask = 0;
        for (unsigned g = 0; g < w; g += 4) { /* four lanes at a time */
            const char *base = (const char *)q + 4 * g;
#define SLAB(k)                                                                              \
    lo_t = _mm_max_ps(lo_t, _mm_mul_ps(_mm_sub_ps(_mm_load_ps((const float *)(base + f->near##k)), \
                                                  f->of##k),                                 \
                                       f->invf##k));                                         \
    hi_t = _mm_min_ps(hi_t, _mm_mul_ps(_mm_sub_ps(_mm_load_ps((const float *)(base + f->far##k)),  \
                                                  f->of##k),                                 \
                                       f->invf##k))
            __m128 lo_t = _mm_set1_ps(t0f), hi_t = _mm_set1_ps(t1f);
            SLAB(0);
            SLAB(1);
            SLAB(2);
#undef SLAB
            _mm_storeu_ps(e + g, lo_t);
            mask |= (unsigned)_mm_movemask_ps(_mm_cmple_ps(lo_t, hi_t)) << g;
        }
        return mask;
    }
#else
    (void)f;
    (void)t0f;
    (void)t1f;
    (void)use_float;
#endif
    const char *base = (const char *)q;
    unsigned mask = 0;
    for (unsigned c = 0; c < w; c++) {
        double a0 = t0, a1 = t1;
        for (unsigned k = 0; k < 3; k++) {
            const float *nf = (const float *)(base + r->near[k]);
            const float *ff = (const float *)(base + r->far[k]);
            double a = ((double)nf[c] - r->o[k]) * r->inv[k];
            double b = ((double)ff[c] - r->o[k]) * r->inv[k];
            a0 = a > a0 ? a : a0;
            a1 = b < a1 ? b : a1;
        }
        e[c] = bvh_float_down(a0);
        mask |= (unsigned)(a0 <= a1) << c;
    }
    return mask;
}

/* The walk's stack: a node's index and meta (bvh.h) and its entry. One
 * wide node pushes W - 1 at most, so W - 1 per level and the root suffice. */
#define WIDE_STACK ((BVH_WIDEST - 1) * BVH_MAX_DEPTH + 2)

/* The walk of T (width W), whose root's box R meets (wide_ray_root), for R
 * over [TMIN, C->tmax] (which shrinks as closest-hit leaves find hits),
 * ANY: stop at the first hit; returns 1 when it did. *TESTED counts the box
 * tests. Inlined per width and path (W and USE_FLOAT constant). */
static inline __attribute__((always_inline)) int
walk_wide(const bvh *t, unsigned w, const wide_ray *r, double tmin, query_state *c, int any,
          int use_float, uint64_t *tested)
{
    const double sh = use_float ? r->scale : 1.0;
    const float tmin_f = t_down(tmin, sh);
    float best_f = t_up(c->tmax, sh);
    uint32_t st_index[WIDE_STACK], st_meta[WIDE_STACK];
    float st_entry[WIDE_STACK];
    unsigned sp = 0;
    uint64_t nodes = 0; /* counted here, added to *TESTED at the end: the
                         * loop keeps it in a register */
    int found = 0;
    uint32_t index = t->root.index, meta = t->root.meta;
    const float_slabs f = {
#if defined(__SSE2__)
        r->of[0], r->of[1], r->of[2], r->invf[0], r->invf[1], r->invf[2],
#endif
        r->near[0], r->near[1], r->near[2], r->far[0], r->far[1], r->far[2]};
    const size_t node_bytes = BVH_WIDE_BYTES(w);
    for (;;) {
        if (meta >> 2) { /* a leaf */
            double before = c->tmax;
            if (leaf_records(c, index, meta >> 2, any)) {
                found = 1;
                break;
            }
            if (c->tmax != before)
                best_f = t_up(c->tmax, sh);
        } else {
            const unsigned char *q = t->wide + (size_t)index * node_bytes;
            /* the lanes' indices and metas (bvh.h), read as the walk needs them */
            const unsigned char *qi = q + 4 * 6 * w, *qm = q + 4 * 7 * w;
            float e[BVH_WIDEST];
            unsigned hit = wide_hit(q, w, r, &f, tmin, c->tmax, tmin_f, best_f, e, use_float);
            nodes++;
            if (hit) {
                unsigned first = (unsigned)__builtin_ctz(hit);
                hit &= hit - 1;
                if (!hit) { /* one box met: enter it */
                    memcpy(&index, qi + 4 * first, sizeof index);
                    memcpy(&meta, qm + 4 * first, sizeof meta);
                    continue;
                }
                /* several: push them farthest first, enter the nearest */
                unsigned lane[BVH_WIDEST], m = 0;
                lane[m++] = first;
                while (hit) {
                    unsigned l = (unsigned)__builtin_ctz(hit);
                    hit &= hit - 1;
                    unsigned j = m++;
                    for (; j > 0 && e[lane[j - 1]] < e[l]; j--)
                        lane[j] = lane[j - 1];
                    lane[j] = l;
                }
                for (unsigned j = 0; j + 1 < m; j++) {
                    memcpy(&st_index[sp], qi + 4 * lane[j], sizeof index);
                    memcpy(&st_meta[sp], qm + 4 * lane[j], sizeof meta);
                    st_entry[sp] = e[lane[j]];
                    /* its first two lines (a wide node's lower faces, a leaf's
                     * first record), loaded while the nearer subtree is walked:
                     * on the 871,414-triangle dragon +11 % (bvh8), on scenes whose
                     * tree fits the caches no change (docs/bvh.md) */
                    const char *p = st_meta[sp] >> 2
                                        ? (const char *)(c->rec + st_index[sp])
                                        : (const char *)(t->wide + (size_t)st_index[sp] * node_bytes);
                    __builtin_prefetch(p);
                    __builtin_prefetch(p + 64);
                    sp++;
                }
                memcpy(&index, qi + 4 * lane[m - 1], sizeof index);
                memcpy(&meta, qm + 4 * lane[m - 1], sizeof meta);
                continue;
            }
        }
        while (sp && st_entry[sp - 1] > best_f) /* beyond the best hit */
            sp--;
        if (!sp)
            break;
        sp--;
        index = st_index[sp];
        meta = st_meta[sp];
    }
    *tested += w * nodes;
    return found;
}

/* The walks of width 4 and 8 on the path R allows, a function each (each
 * compiled as if alone; one function of both measured the same). */
static __attribute__((noinline)) int walk_ray4(const bvh *t, const wide_ray *r, int use_float,
                                               double tmin, query_state *c, int any,
                                               uint64_t *tested)
{
    return use_float ? walk_wide(t, 4, r, tmin, c, any, 1, tested)
                     : walk_wide(t, 4, r, tmin, c, any, 0, tested);
}
static __attribute__((noinline)) int walk_ray8(const bvh *t, const wide_ray *r, int use_float,
                                               double tmin, query_state *c, int any,
                                               uint64_t *tested)
{
    return use_float ? walk_wide(t, 8, r, tmin, c, any, 1, tested)
                     : walk_wide(t, 8, r, tmin, c, any, 0, tested);
}

/* Closest hit into HIT, or occlusion when HIT is NULL. */
static inline __attribute__((always_inline)) int query_wide(const bsp_accel *a, bsp_query *q,
                                                        const bsp_ray *ray, uint32_t from,
                                                        bsp_hit *hit)
{
    int out;
    if (query_without_walk(a, q, ray, from, hit, &out))
        return out;
    const bvh *t = a->impl;
    wide_ray r;
    if (!wide_ray_root(&r, t, ray)) {
        query_count(q, 1, 0, 0, 0, 0, 0); /* the root's box */
        return 0;
    }
    int fl = wide_ray_float(&r, t, ray);
    query_state c;
    query_start(&c, a->scene, t, ray, from);
    uint64_t tested = 1;
    int found = t->width == 8 ? walk_ray8(t, &r, fl, ray->tmin, &c, !hit, &tested)
                              : walk_ray4(t, &r, fl, ray->tmin, &c, !hit, &tested);
    int closest = query_finish(q, &c, tested, hit);
    return hit ? closest : found;
}

int bvh_wide_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                       bsp_hit *hit)
{
    return query_wide(a, q, ray, from, hit);
}

int bvh_wide_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    return query_wide(a, q, ray, from, NULL);
}
