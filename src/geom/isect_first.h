/*
 * isect_first.h — the first tests of the sphere, cone, triangle and polygon
 * kernels, written once for any arithmetic type: geom/isect.h includes it for double
 * (its kernels call these), accel/naive_blocks.c for vectors of two doubles
 * (four primitives tested at a time). One text, so the same operations in
 * the same order: every lane of a vector computes the bits the kernel
 * computes, and a block rejects exactly the primitives whose kernel returns
 * at that test. No include guard: a template, included once per type.
 *
 * The includer defines
 *   ISECT_T             the type (double, or a vector of doubles)
 *   ISECT_MASK          what a comparison of two ISECT_T gives
 *   ISECT_FIRST(name)   the name of a function for this type
 *   ISECT_NEG_WHERE(m, x)  -x where mask m is set, x elsewhere
 *   ISECT_ZERO          zero of type ISECT_T
 *   ISECT_ABS(x)        |x| (the sign bit cleared, exact)
 * and undefines them afterwards. Every function is static inline and always
 * inlined; the outputs by pointer vanish after inlining.
 */

#if !defined(ISECT_T) || !defined(ISECT_MASK) || !defined(ISECT_FIRST) ||                      \
    !defined(ISECT_NEG_WHERE) || !defined(ISECT_ZERO) || !defined(ISECT_ABS)
#error "isect_first.h needs ISECT_T, ISECT_MASK, ISECT_FIRST, ISECT_NEG_WHERE, ISECT_ZERO, ISECT_ABS"
#endif

/* The sphere's discriminant (sphere_isect): for the origin OC = org - centre
 * and the direction D with A = dot(d, d) > 0, b = dot(oc, d) and
 * disc = a (r^2 - |l|^2), l = oc - (b / a) d being the ray's point nearest
 * the centre (less cancellation than b^2 - a c). A miss unless disc >= 0. */
static inline __attribute__((always_inline)) ISECT_T
ISECT_FIRST(sphere_disc)(ISECT_T ocx, ISECT_T ocy, ISECT_T ocz, ISECT_T dx, ISECT_T dy,
                         ISECT_T dz, ISECT_T a, ISECT_T radius2, ISECT_T *b_out)
{
    ISECT_T b = ocx * dx + ocy * dy + ocz * dz;
    ISECT_T s = -(b / a);
    ISECT_T lx = ocx + dx * s, ly = ocy + dy * s, lz = ocz + dz * s;
    *b_out = b;
    return a * (radius2 - (lx * lx + ly * ly + lz * lz));
}

/* Whether the origin OC = org - base lies farther from a cone's base than
 * FAR2 allows (cone_shape.far2): then the cone is solved from a moved
 * origin (below). */
static inline __attribute__((always_inline)) ISECT_MASK
ISECT_FIRST(cone_origin_far)(ISECT_T ocx, ISECT_T ocy, ISECT_T ocz, ISECT_T far2)
{
    return ocx * ocx + ocy * ocy + ocz * ocz > far2;
}

/* The cone's origin moved along the ray (cone_isect, for an origin far from
 * the base): TS = dot(mid - org, d) / dd puts it at the ray's point nearest
 * the axis's middle MID; writes that point less the base B in *OC. */
static inline __attribute__((always_inline)) ISECT_T
ISECT_FIRST(cone_moved_origin)(ISECT_T ox, ISECT_T oy, ISECT_T oz, ISECT_T dx, ISECT_T dy,
                               ISECT_T dz, ISECT_T dd, ISECT_T mx, ISECT_T my, ISECT_T mz,
                               ISECT_T bx, ISECT_T by, ISECT_T bz, ISECT_T *ocx, ISECT_T *ocy,
                               ISECT_T *ocz)
{
    ISECT_T ts = ((mx - ox) * dx + (my - oy) * dy + (mz - oz) * dz) / dd;
    *ocx = (ox + dx * ts) - bx;
    *ocy = (oy + dy * ts) - by;
    *ocz = (oz + dz * ts) - bz;
    return ts;
}

/* The cone's quadratic qa t^2 + 2 qb t + qc = 0 (cone_isect) for the origin
 * OC = org - base (or the moved one), the direction D, the unit axis A, the
 * base radius BR and the slope: h0 and hd the heights of oc and d along the
 * axis, po and pd their parts across it, ro and rd the radius at oc's height
 * and its rate. Returns the discriminant qb^2 - qa qc: when qa != 0 a miss
 * unless it is >= 0 (qa == 0 is the kernel's linear case). */
static inline __attribute__((always_inline)) ISECT_T
ISECT_FIRST(cone_quadratic)(ISECT_T ocx, ISECT_T ocy, ISECT_T ocz, ISECT_T dx, ISECT_T dy,
                            ISECT_T dz, ISECT_T ax, ISECT_T ay, ISECT_T az, ISECT_T base_radius,
                            ISECT_T slope, ISECT_T *h0_out, ISECT_T *hd_out, ISECT_T *qa_out,
                            ISECT_T *qb_out, ISECT_T *qc_out)
{
    ISECT_T h0 = ocx * ax + ocy * ay + ocz * az, hd = dx * ax + dy * ay + dz * az;
    ISECT_T nh0 = -h0, nhd = -hd;
    ISECT_T pox = ocx + ax * nh0, poy = ocy + ay * nh0, poz = ocz + az * nh0;
    ISECT_T pdx = dx + ax * nhd, pdy = dy + ay * nhd, pdz = dz + az * nhd;
    ISECT_T ro = base_radius + slope * h0, rd = slope * hd;
    ISECT_T qa = (pdx * pdx + pdy * pdy + pdz * pdz) - rd * rd;
    ISECT_T qb = (pox * pdx + poy * pdy + poz * pdz) - ro * rd;
    ISECT_T qc = (pox * pox + poy * poy + poz * poz) - ro * ro;
    *h0_out = h0;
    *hd_out = hd;
    *qa_out = qa;
    *qb_out = qb;
    *qc_out = qc;
    return qb * qb - qa * qc;
}

/* Möller–Trumbore's determinant and unnormalised barycentrics (triangle_solve)
 * for the direction D and TV = org - v0, with the edges E1 = v1 - v0 and
 * E2 = v2 - v0: pvec = d x e2, det = e1 . pvec, bu = tv . pvec,
 * qvec = tv x e1 (in *Q, for the kernel's t), bv = d . qvec. */
static inline __attribute__((always_inline)) void
ISECT_FIRST(triangle_bary)(ISECT_T dx, ISECT_T dy, ISECT_T dz, ISECT_T tx, ISECT_T ty, ISECT_T tz,
                           ISECT_T e1x, ISECT_T e1y, ISECT_T e1z, ISECT_T e2x, ISECT_T e2y,
                           ISECT_T e2z, ISECT_T *det, ISECT_T *bu, ISECT_T *bv, ISECT_T *qx,
                           ISECT_T *qy, ISECT_T *qz)
{
    ISECT_T px = dy * e2z - dz * e2y, py = dz * e2x - dx * e2z, pz = dx * e2y - dy * e2x;
    *det = e1x * px + e1y * py + e1z * pz;
    *bu = tx * px + ty * py + tz * pz;
    *qx = ty * e1z - tz * e1y;
    *qy = tz * e1x - tx * e1z;
    *qz = tx * e1y - ty * e1x;
    *bv = dx * *qx + dy * *qy + dz * *qz;
}

/* The margin past which Möller–Trumbore's own signs decide (triangle_solve):
 * SCALE (T E) for the origin's offset TV = org - v0, with E = 2^k >
 * |e1|_1 + |e2|_1 (ENORM, triangle_edge_norm), T = |tv|_1 + E and
 * SCALE = 2^-40 |d|_1 (isect_ray.edge_scale). For a ray passing within the
 * triangle's size of it, det, bu, bv and det - (bu + bv), and the watertight
 * test's edge functions brought to the same scale, err by less than
 * 2^-47 |d| T E (docs/precision.md): a value past the margin has the sign
 * exact arithmetic gives it, in both tests. */
static inline __attribute__((always_inline)) ISECT_T
ISECT_FIRST(triangle_margin)(ISECT_T tx, ISECT_T ty, ISECT_T tz, ISECT_T enorm, ISECT_T scale)
{
    ISECT_T tn = (ISECT_ABS(tx) + ISECT_ABS(ty) + ISECT_ABS(tz)) + enorm;
    return scale * (tn * enorm);
}

/* The sign of DET folded into *DET, *BU and *BV (made the positive
 * determinant's), NEG the mask of where it was negative; returns where the
 * ray may pass inside: det != 0 and none of bu, bv and det - (bu + bv)
 * below -M, the margin (all three at least -M: with M = 0, the barycentric
 * range). A miss where it fails; past the margin inside, a hit; between,
 * the watertight test decides (triangle_solve). NaN fails. */
static inline __attribute__((always_inline)) ISECT_MASK
ISECT_FIRST(triangle_range)(ISECT_T *det, ISECT_T *bu, ISECT_T *bv, ISECT_T m, ISECT_MASK *neg)
{
    *neg = *det < ISECT_ZERO;
    *det = ISECT_NEG_WHERE(*neg, *det);
    *bu = ISECT_NEG_WHERE(*neg, *bu);
    *bv = ISECT_NEG_WHERE(*neg, *bv);
    ISECT_T lo = -m;
    return (*det != ISECT_ZERO) & (*bu >= lo) & (*bv >= lo) & (*det - (*bu + *bv) >= lo);
}

/* The polygon's plane (polygon_isect): DENOM = n . d (in *DENOM; a miss when
 * 0) and the t of the plane's point, (dist - n . org) / denom, for the unit
 * normal N and the plane's distance DIST from the origin. */
static inline __attribute__((always_inline)) ISECT_T
ISECT_FIRST(polygon_plane)(ISECT_T nx, ISECT_T ny, ISECT_T nz, ISECT_T dist, ISECT_T ox,
                           ISECT_T oy, ISECT_T oz, ISECT_T dx, ISECT_T dy, ISECT_T dz,
                           ISECT_T *denom)
{
    *denom = nx * dx + ny * dy + nz * dz;
    return (dist - (nx * ox + ny * oy + nz * oz)) / *denom;
}
