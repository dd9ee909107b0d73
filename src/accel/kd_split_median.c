/*
 * kd_split_median.c — Kaplan's BSP: every node is cut at the spatial median
 * of its box, the axes taken in turn x, y, z by depth; a node becomes a leaf
 * at the depth limit or with at most max_leaf_prims primitives (the paper:
 * 18 and 2). And the octree of centre subdivision (Glassner 1984, as Havran's
 * 1999 octree statistics built it), which is the same tree decided only every
 * third level: an octree node that is not a leaf is cut in x, both halves in
 * y and the four quarters in z, so its eight octants are all made (empty ones
 * as empty leaves), and each octant is an octree node one level down. The
 * adaptive octree (Octree-R, Havran's Octree84-A) is the same tree with its
 * three planes chosen at the octree node by a cost estimate (octree_planes);
 * the two lower levels of the group cut at the planes chosen above them.
 *
 * Primitive lists live in one growable scratch stack: a node's list is at
 * [base, base + n), its children's lists are written at the first free index
 * above it, and the left subtree works above both, so the right list
 * survives until its turn. Everything is addressed by index, so growing the stack is safe.
 */
#include <stdlib.h>

#include "accel/kd_tree.h"
#include "util/grow.h"

typedef struct median_build {
    kd_tree *t;
    bsp_box *pbox; /* padded bounds per primitive */
    uint32_t *scratch;
    size_t cap;
    int group; /* levels per decision: 1 Kaplan, 3 the octree */
    int by_cost; /* the octree: planes by octree_planes, not at the centre */
    double *centres; /* by_cost: scratch for the primitives' centres (median) */
    size_t centres_cap;
    bsp_error *err;
} median_build;

/* Havran's 1999 adaptive octrees (Octree84-A): the candidate planes per axis,
 * the box's centre and the positions a tenth, two tenths, ... nine tenths of
 * the way to the median of its primitives (octree_planes). */
#define OCTREE_COST_CANDIDATES 10

/* The K-th smallest of A[0..N) (K < N; A is reordered): quickselect with
 * a median-of-three pivot and a three-way partition, so runs of equal
 * values (centres clamped to a face of the box) cost one pass. O(N)
 * expected; the value is the sorted array's A[K] whatever the order. */
static double select_kth(double *a, size_t n, size_t k)
{
    size_t lo = 0, hi = n; /* the answer lies in a[lo..hi) */
    while (hi - lo > 1) {
        double x = a[lo], y = a[lo + (hi - lo) / 2], z = a[hi - 1];
        double pivot = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
        /* a[lo..lt) < pivot, a[lt..i) == pivot, a(gt..hi) > pivot */
        size_t lt = lo, i = lo, gt = hi;
        while (i < gt) {
            double v = a[i];
            if (v < pivot) {
                a[i++] = a[lt];
                a[lt++] = v;
            } else if (v > pivot) {
                a[i] = a[--gt];
                a[gt] = v;
            } else {
                i++;
            }
        }
        if (k < lt)
            hi = lt;
        else if (k >= gt)
            lo = gt;
        else
            return pivot;
    }
    return a[lo];
}

/* The estimate Havran states for his adaptive octrees (after MacDonald and
 * Booth, and Whang et al.'s Octree-R): a plane at T from the low face of a
 * box A x B x C (A along the axis), with LEFT primitives wholly below it,
 * RIGHT wholly above and CUT across it, costs (LEFT + CUT)(2T(B + C) + BC) +
 * (RIGHT + CUT)(2(A - T)(B + C) + BC). Taken as he gives it. */
static double octree_plane_cost(double a, double b, double c, double t, size_t left,
                                size_t right, size_t cut)
{
    return (double)(left + cut) * (t * 2.0 * (b + c) + b * c) +
           (double)(right + cut) * ((a - t) * 2.0 * (b + c) + b * c);
}

/* The octree node's three planes into PLANES: on each axis the least-cost
 * of OCTREE_COST_CANDIDATES positions from the centre of BOX (included)
 * towards the median of the primitives LIST[0..N) (excluded), the one
 * nearest the centre on a tie. The median is the middle one (index N/2,
 * ascending) of the centres of the primitives' padded bounds clipped to
 * BOX. Havran's text leaves these three choices open (which centres, which
 * median, whether the ends are candidates); these are the ones whose trees
 * come nearest his over his scenes (docs/octree.md). A primitive counts left
 * when its padded bounds start below the plane and right when they end above
 * it, as the lists are then split. A candidate whose float is not strictly
 * inside the box is passed over; the centre is the fallback. Returns 0 when
 * out of memory. */
static int octree_planes(median_build *b, bsp_box box, const uint32_t *list, size_t n,
                         double planes[3])
{
    if (!GROW_ARRAY(b->centres, b->centres_cap, n))
        return 0;
    for (unsigned k = 0; k < 3; k++) {
        double lo = box.lo.v[k], hi = box.hi.v[k];
        double centre = 0.5 * (lo + hi);
        for (size_t j = 0; j < n; j++) {
            const bsp_box *p = &b->pbox[list[j]];
            double plo = p->lo.v[k] > lo ? p->lo.v[k] : lo, phi = p->hi.v[k] < hi ? p->hi.v[k] : hi;
            b->centres[j] = 0.5 * (plo + phi);
        }
        double median = select_kth(b->centres, n, n / 2);
        double a = hi - lo, e1 = box.hi.v[(k + 1) % 3] - box.lo.v[(k + 1) % 3],
               e2 = box.hi.v[(k + 2) % 3] - box.lo.v[(k + 2) % 3];
        double best_cost = 0.0;
        planes[k] = centre;
        int found = 0;
        for (int i = 0; i < OCTREE_COST_CANDIDATES; i++) {
            double p = centre + (median - centre) * i / OCTREE_COST_CANDIDATES;
            double s = (double)(float)p;
            if (!(s > lo && s < hi))
                continue;
            size_t left = 0, right = 0, cut = 0;
            for (size_t j = 0; j < n; j++) {
                const bsp_box *q = &b->pbox[list[j]];
                int l = q->lo.v[k] < s, r = q->hi.v[k] > s;
                left += l && !r;
                right += r && !l;
                cut += l && r;
            }
            double cost = octree_plane_cost(a, e1, e2, s - lo, left, right, cut);
            if (!found || cost < best_cost) {
                best_cost = cost;
                planes[k] = s;
                found = 1;
            }
        }
    }
    return 1;
}

static int reserve(median_build *b, size_t need)
{
    return GROW_ARRAY(b->scratch, b->cap, need);
}

static bsp_status oom(median_build *b)
{
    return kd_build_failed(b->t, b->err);
}

/* The node's list is scratch[base, base + n); scratch[top, ...) is free.
 * PLANES: with by_cost, the planes its octree node chose (read at the two
 * lower levels of the group; set here at the first). */
static bsp_status build_node(median_build *b, uint32_t node, bsp_box box, size_t base, size_t n,
                             size_t top, int depth, double planes[3])
{
    kd_tree *t = b->t;
    unsigned axis = (unsigned)(depth % 3);
    double lo = box.lo.v[axis], hi = box.hi.v[axis];
    /* a leaf by the limits (decided at a node of the group's first level), or
     * when the box is too thin for a float plane */
    int decides = depth % b->group == 0;
    if (decides && (n <= (size_t)t->max_leaf_prims || depth >= t->max_depth))
        return kd_make_leaf(t, node, b->scratch + base, n) ? BSP_OK : oom(b);
    double own[3];
    if (b->by_cost && decides) {
        if (!octree_planes(b, box, b->scratch + base, n, own))
            return oom(b);
        planes = own;
    }
    float split = b->by_cost ? (float)planes[axis] : (float)(0.5 * (lo + hi));
    double s = (double)split;
    if (!(s > lo && s < hi))
        return kd_make_leaf(t, node, b->scratch + base, n) ? BSP_OK : oom(b);

    if (!reserve(b, top + 2 * n))
        return oom(b);
    size_t left = top, nl = 0;
    for (size_t k = 0; k < n; k++) {
        uint32_t p = b->scratch[base + k];
        if (b->pbox[p].lo.v[axis] < s)
            b->scratch[left + nl++] = p;
    }
    size_t right = left + nl, nr = 0;
    for (size_t k = 0; k < n; k++) {
        uint32_t p = b->scratch[base + k];
        if (b->pbox[p].hi.v[axis] > s)
            b->scratch[right + nr++] = p;
    }
    uint32_t child = kd_alloc_pair(t);
    if (child == UINT32_MAX)
        return oom(b);
    kd_make_interior(t, node, axis, split, child);
    bsp_box lb = box, rb = box;
    lb.hi.v[axis] = rb.lo.v[axis] = s;
    /* the left subtree works above both lists; then the right one may reuse it */
    bsp_status st = build_node(b, child, lb, left, nl, right + nr, depth + 1, planes);
    if (st == BSP_OK)
        st = build_node(b, child + 1, rb, right, nr, right + nr, depth + 1, planes);
    return st;
}

static bsp_status build_median(kd_tree *t, const bsp_scene *scene, int group, int by_cost,
                               bsp_error *err)
{
    size_t np = bsp_scene_prim_count(scene);
    median_build b = {t, NULL, NULL, 0, group, by_cost, NULL, 0, err};
    b.pbox = malloc((np ? np : 1) * sizeof *b.pbox);
    b.cap = 4 * np + 64;
    b.scratch = malloc(b.cap * sizeof *b.scratch);
    bsp_status st = BSP_OK;
    if (!b.pbox || !b.scratch) {
        st = oom(&b);
    } else {
        size_t n = 0;
        for (uint32_t p = 0; p < np; p++) {
            if (bsp_scene_prim_kind(scene, p) == BSP_PRIM_DROPPED)
                continue;
            b.pbox[p] = kd_prim_box(t, scene, p);
            b.scratch[n++] = p;
        }
        double planes[3] = {0.0, 0.0, 0.0};
        if (n > 0)
            st = build_node(&b, 0, t->box, 0, n, n, 0, planes);
    }
    free(b.centres);
    free(b.pbox);
    free(b.scratch);
    return st;
}

bsp_status kd_build_median(kd_tree *t, const bsp_scene *scene, bsp_error *err)
{
    return build_median(t, scene, 1, 0, err);
}

bsp_status kd_build_octree(kd_tree *t, const bsp_scene *scene, bsp_octree_split split,
                           bsp_error *err)
{
    t->octree = 1;
    return build_median(t, scene, 3, split == BSP_OCTREE_COST, err);
}

int kd_octree_default_depth(size_t n)
{
    /* the least d with 8^d >= 8 N: about eight finest cells per primitive. On
     * the SPD scenes (N 4,096 to 9,345) that is 5 or 6, within 20 % of each
     * scene's fastest depth but tree's (docs/octree.md) */
    int d = 1;
    for (double cells = 8.0; cells < 8.0 * (double)n && d < BSP_OCTREE_MAX_DEPTH; cells *= 8.0)
        d++;
    return d;
}
