/* Segment clipping in OpenCL C: RNSCA (exact and approx leaves) and the baselines, and
 * the run-level pruning of lines and rings (at the end of the file).
 *
 * One source for every device and precision, parameterised by build options:
 *   -DREAL_IS_DOUBLE=1   float64 (needs cl_khr_fp64); 0: float32
 *   -DLOCAL_SIZE=64      work-items per group (the stats are reduced per group)
 *   -DLEFT=1 ...         every constant this file shares with the Numba kernels (outcode
 *                        bits, edge and method ids, the counter row, N's bounds, stack
 *                        sizes, decision codes): defined once, in rnsca/constants.py, and
 *                        passed by rnsca.backends.opencl.constant_options. This file
 *                        defines none of them (tests/unit/test_constants.py checks).
 * Each function is a line-by-line port of the Numba kernel of the same name
 * (rnsca/kernels/outcode.py, segments.py, the modules of rnsca/baselines): the same
 * formulas in the same order, so in float64 the pieces agree with the Numba backend's to
 * rounding (in practice bit for bit). Read those modules for the geometry and the
 * reasons; the comments here only note what differs in C.
 *
 * Variable-length output in three passes (see rnsca/backends/opencl/__init__.py):
 * `clip_segments` clips one segment per work-item and stores its result and a 0/1 count;
 * the host runs a prefix sum over the counts; `write_pieces` copies the kept results
 * to their slots.
 */

/* The error-free transformations (TwoSum, Dekker's TwoProduct) need every product and
 * sum rounded on its own: a fused multiply-add would break them, and Numba never fuses. */
#pragma OPENCL FP_CONTRACT OFF

#if REAL_IS_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double REAL;
/* Veltkamp's splitter 2**27 + 1, for Dekker's exact product without FMA. */
#define SPLITTER 134217729.0
/* Four roundings: 4 eps. */
#define EPS4 8.881784197001252e-16
/* A few subnormal steps, where error terms underflow (see interpolation_margin). */
#define SUBNORMAL_FLOOR 1e-322
#define SUBNORMAL_STEP 1e-323
/* Below this magnitude double-double error terms underflow and stop being exact. */
#define UNDERFLOW_LIMIT 1e-290
/* NLN: products of numbers within these magnitudes neither overflow nor underflow. */
#define NLN_BIG 0x1p500
#define NLN_SMALL 0x1p-500
#else
typedef float REAL;
/* The float32 counterparts: splitter 2**12 + 1, eps 2**-24, subnormal steps of 2**-149,
 * double-double terms exact above FLT_MIN / eps**2, products safe within 2**+-60. */
#define SPLITTER 4097.0f
#define EPS4 2.384185791015625e-07f
#define SUBNORMAL_FLOOR 2.8e-44f
#define SUBNORMAL_STEP 1.4e-45f
#define UNDERFLOW_LIMIT 1e-22f
#define NLN_BIG 0x1p60f
#define NLN_SMALL 0x1p-60f
#endif

#define INF_REAL ((REAL)INFINITY)

/* The shared constants (outcode bits, method ids, counter slots, ...) are build options
 * (see the top of this file); a build without them fails here rather than at their
 * first use. */
#ifndef COUNTERS_WIDTH
#error "build with the options of rnsca.backends.opencl.constant_options (rnsca/constants.py)"
#endif

/* Stats are summed in local memory per work-group (32-bit atomics are core OpenCL;
 * one segment adds at most a few thousand to any counter) and the group's row is
 * written once. */
typedef __local int *Counters;
#define COUNT(st, k, v) atomic_add(&(st)[k], (int)(v))

/* Helpers are plain functions, not `inline`: C99 inline semantics would leave some
 * compilers without a definition at -cl-opt-disable; the optimizers inline them anyway. */

/* Python's min and max (the first argument wins ties), not fmin/fmax. */
REAL py_min(REAL a, REAL b) { return b < a ? b : a; }
REAL py_max(REAL a, REAL b) { return b > a ? b : a; }

/* --- outcode.py ------------------------------------------------------------------- */

int outcode(REAL x, REAL y, REAL xmin, REAL ymin, REAL xmax, REAL ymax) {
    return ((x < xmin) * LEFT) | ((x > xmax) * RIGHT) | ((y < ymin) * BOTTOM)
           | ((y > ymax) * TOP);
}

int wide(int code) { return code | (code << SURE_SHIFT); }

/* A box, or a window: [xmin, xmax] x [ymin, ymax]. */
typedef struct {
    REAL xmin, ymin, xmax, ymax;
} Box;

/* The box stored as v[0..3] = (xmin, ymin, xmax, ymax). */
Box box_at(__global const REAL *v) {
    Box b = {v[0], v[1], v[2], v[3]};
    return b;
}

Box point_box(REAL x, REAL y) {
    Box b = {x, y, x, y};
    return b;
}

Box box_union(Box a, Box b) {
    Box u = {py_min(a.xmin, b.xmin), py_min(a.ymin, b.ymin), py_max(a.xmax, b.xmax),
             py_max(a.ymax, b.ymax)};
    return u;
}

int box_outcode(REAL x, REAL y, Box w) {
    return outcode(x, y, w.xmin, w.ymin, w.xmax, w.ymax);
}

REAL clamp_real(REAL v, REAL low, REAL high) { return py_min(py_max(v, low), high); }

/* (s, *err) with s + *err == a + b exactly (Knuth's TwoSum). */
REAL two_sum(REAL a, REAL b, REAL *err) {
    REAL s = a + b;
    REAL v = s - a;
    *err = (a - (s - v)) + (b - v);
    return s;
}

/* (p, *err) with p + *err == a * b exactly (Dekker's TwoProduct, Veltkamp's splits). */
REAL two_product(REAL a, REAL b, REAL *err) {
    REAL p = a * b;
    REAL c = SPLITTER * a;
    REAL ah = c - (c - a);
    REAL al = a - ah;
    c = SPLITTER * b;
    REAL bh = c - (c - b);
    REAL bl = b - bh;
    *err = (((ah * bh - p) + ah * bl) + al * bh) + al * bl;
    return p;
}

/* a = a0 + t * da as rounded, and its error (TwoProduct, TwoSum). */
REAL interpolate_dd(REAL a0, REAL da, REAL da_err, REAL t, REAL *err) {
    REAL p_err, a_err;
    REAL p = two_product(t, da, &p_err);
    REAL a = two_sum(a0, p, &a_err);
    *err = a_err + p_err + t * da_err;
    return a;
}

REAL interpolation_margin(REAL err, REAL a0, REAL da, REAL *margin) {
    if (!isfinite(err)) {
        *margin = EPS4 * fabs(a0) + EPS4 * fabs(da) + SUBNORMAL_STEP;
        return 0;
    }
    REAL floor_ = (da != 0 && fabs(da) < UNDERFLOW_LIMIT) ? SUBNORMAL_FLOOR : 0;
    *margin = fabs(err) * EPS4 + floor_;
    return err;
}

void interpolated_point(REAL x0, REAL y0, REAL dx, REAL dx_err, REAL dy, REAL dy_err,
                               REAL t, REAL *x, REAL *y, REAL *cx, REAL *mx, REAL *cy,
                               REAL *my) {
    REAL x_err, y_err;
    *x = interpolate_dd(x0, dx, dx_err, t, &x_err);
    *y = interpolate_dd(y0, dy, dy_err, t, &y_err);
    *cx = interpolation_margin(x_err, x0, dx, mx);
    *cy = interpolation_margin(y_err, y0, dy, my);
}

int wide_outcode(REAL x, REAL y, REAL cx, REAL mx, REAL cy, REAL my, REAL xmin,
                        REAL ymin, REAL xmax, REAL ymax) {
    REAL dl = (x - xmin) + cx;
    REAL dr = (xmax - x) - cx;
    REAL db = (y - ymin) + cy;
    REAL dt = (ymax - y) - cy;
    int unsure = ((dl < mx) * LEFT) | ((dr < mx) * RIGHT) | ((db < my) * BOTTOM)
                 | ((dt < my) * TOP);
    int sure = ((-dl > mx) * LEFT) | ((-dr > mx) * RIGHT) | ((-db > my) * BOTTOM)
               | ((-dt > my) * TOP);
    return unsure | (sure << SURE_SHIFT);
}

/* (d, d_err) with d + d_err == x1 - x0 exactly (TwoSum of x1 and -x0). */
REAL difference_dd(REAL x1, REAL x0, REAL *d_err) { return two_sum(x1, -x0, d_err); }

/* b + ((e - a) / da) * db in double-double; returns the rounded value, *residual the rest. */
REAL line_coordinate_dd(REAL e, REAL a, REAL b, REAL da, REAL da_err, REAL db,
                               REAL db_err, REAL *residual) {
    REAL s_err, r_err, p_err, y_err;
    REAL s = difference_dd(e, a, &s_err);
    REAL t = s / da;
    REAL r = two_product(t, da, &r_err);
    REAL t_lo = ((((s - r) - r_err) + s_err) - t * da_err) / da;
    REAL p = two_product(t, db, &p_err);
    p_err = p_err + (t_lo * db + t * db_err);
    REAL y = two_sum(b, p, &y_err);
    return two_sum(y, y_err + p_err, residual);
}

REAL line_coordinate_residual(REAL e, REAL a0, REAL b0, REAL a1, REAL b1,
                                     REAL *residual) {
    int near1 = fabs(e - a1) < fabs(e - a0);
    REAL a = near1 ? a1 : a0;
    REAL b = near1 ? b1 : b0;
    REAL da_err, db_err;
    REAL da = difference_dd(a1, a0, &da_err);
    REAL db = difference_dd(b1, b0, &db_err);
    REAL rest;
    REAL precise = line_coordinate_dd(e, a, b, da, da_err, db, db_err, &rest);
    if (isfinite(precise) && isfinite(rest)) {
        *residual = rest;
        return precise;
    }
    *residual = 0;
    return b + (e - a) / da * db;
}

REAL line_coordinate(REAL e, REAL a0, REAL b0, REAL a1, REAL b1) {
    int near1 = fabs(e - a1) < fabs(e - a0);
    REAL a = near1 ? a1 : a0;
    REAL b = near1 ? b1 : b0;
    REAL db = b1 - b0;
    REAL plain = b + (e - a) / (a1 - a0) * db;
    if (fabs(b) + fabs(db) <= 16 * fabs(plain) || fabs(db) < UNDERFLOW_LIMIT)
        return plain;
    REAL residual;
    return line_coordinate_residual(e, a0, b0, a1, b1, &residual);
}

/* edge_point and the outcode of the true point it rounds (Cohen–Sutherland's moves). */
int edge_point_code(REAL x0, REAL y0, REAL x1, REAL y1, int edge, REAL xmin, REAL ymin,
                           REAL xmax, REAL ymax, REAL *x, REAL *y) {
    REAL r;
    if (edge == EDGE_LEFT || edge == EDGE_RIGHT) {
        *x = edge == EDGE_LEFT ? xmin : xmax;
        *y = line_coordinate_residual(*x, x0, y0, x1, y1, &r);
        return wide_outcode(*x, *y, 0, 0, r, 0, xmin, ymin, xmax, ymax) & UNSURE_BITS;
    }
    *y = edge == EDGE_BOTTOM ? ymin : ymax;
    *x = line_coordinate_residual(*y, y0, x0, y1, x1, &r);
    return wide_outcode(*x, *y, r, 0, 0, 0, xmin, ymin, xmax, ymax) & UNSURE_BITS;
}

void edge_point(REAL x0, REAL y0, REAL x1, REAL y1, int edge, REAL xmin, REAL ymin,
                       REAL xmax, REAL ymax, REAL *x, REAL *y) {
    if (edge == EDGE_LEFT) {
        *x = xmin;
        *y = line_coordinate(xmin, x0, y0, x1, y1);
    } else if (edge == EDGE_RIGHT) {
        *x = xmax;
        *y = line_coordinate(xmax, x0, y0, x1, y1);
    } else if (edge == EDGE_BOTTOM) {
        *x = line_coordinate(ymin, y0, x0, y1, x1);
        *y = ymin;
    } else {
        *x = line_coordinate(ymax, y0, x0, y1, x1);
        *y = ymax;
    }
}

void snap_into_window(REAL *x, REAL *y, REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin,
                             REAL ymin, REAL xmax, REAL ymax) {
    if (*y > ymax || *y < ymin) {
        REAL edge = *y > ymax ? ymax : ymin;
        *x = line_coordinate(edge, y0, x0, y1, x1);
        *y = edge;
    }
    if (*x > xmax || *x < xmin) {
        REAL edge = *x > xmax ? xmax : xmin;
        *y = line_coordinate(edge, x0, y0, x1, y1);
        *x = edge;
    }
    *x = clamp_real(*x, xmin, xmax);
    *y = clamp_real(*y, ymin, ymax);
}

void end_point(REAL x0, REAL y0, REAL x1, REAL y1, int edge, REAL px, REAL py,
                      REAL xmin, REAL ymin, REAL xmax, REAL ymax, REAL *x, REAL *y) {
    *x = px;
    *y = py;
    if (edge != NO_EDGE)
        edge_point(x0, y0, x1, y1, edge, xmin, ymin, xmax, ymax, x, y);
    snap_into_window(x, y, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
}

/* A piece is stored as (t0, t1, ax, ay, bx, by): its parameters on the segment and its
 * ends. */
void set_piece(REAL *out, REAL t0, REAL t1, REAL ax, REAL ay, REAL bx, REAL by) {
    out[0] = t0; out[1] = t1; out[2] = ax; out[3] = ay; out[4] = bx; out[5] = by;
}

int is_piece(int degenerate, const REAL *piece) {
    return (piece[0] <= piece[1])
           && (degenerate || piece[2] != piece[4] || piece[3] != piece[5]);
}

/* out = the part [u0, u1] of the segment: an end cut at an edge (e0, e1) on that edge,
 * else (xa, ya) or (xb, yb); both snapped into the window (`end_point`). */
void cut_piece(REAL x0, REAL y0, REAL x1, REAL y1, REAL u0, int e0, REAL xa, REAL ya,
               REAL u1, int e1, REAL xb, REAL yb, REAL xmin, REAL ymin, REAL xmax,
               REAL ymax, REAL *out) {
    out[0] = u0;
    out[1] = u1;
    end_point(x0, y0, x1, y1, e0, xa, ya, xmin, ymin, xmax, ymax, &out[2], &out[3]);
    end_point(x0, y0, x1, y1, e1, xb, yb, xmin, ymin, xmax, ymax, &out[4], &out[5]);
}

/* An analytic baseline's part [u0, u1] of the whole segment, cut at the edges e0 and e1
 * (NO_EDGE: that end not cut): counted (accepted whole, or clipped), and stored in out. */
int baseline_piece(int degenerate, REAL x0, REAL y0, REAL x1, REAL y1, REAL u0, int e0,
                   REAL u1, int e1, REAL xmin, REAL ymin, REAL xmax, REAL ymax, Counters st,
                   REAL *out) {
    COUNT(st, e0 == NO_EDGE && e1 == NO_EDGE ? ACCEPTED : CLIPPED, 1);
    cut_piece(x0, y0, x1, y1, u0, e0, x0, y0, u1, e1, x1, y1, xmin, ymin, xmax, ymax, out);
    return is_piece(degenerate, out);
}

/* --- baselines/liang_barsky.py ------------------------------------------------------ */

/* One half-plane p t <= q applied to [u0, u1]; returns ok. */
int clipt(REAL p, REAL q, int edge, REAL *u0, int *e0, REAL *u1, int *e1, Counters st) {
    if (p == 0)
        return q >= 0;
    REAL r = q / p;
    COUNT(st, INTERSECTIONS, 1);
    if (p < 0) {
        if (r > *u1)
            return 0;
        if (r > *u0) {
            *u0 = r;
            *e0 = edge;
        }
    } else {
        if (r < *u0)
            return 0;
        if (r < *u1) {
            *u1 = r;
            *e1 = edge;
        }
    }
    return 1;
}

int liang_barsky_segment(REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin, REAL ymin,
                                REAL xmax, REAL ymax, Counters st, REAL *out) {
    REAL dx = x1 - x0;
    REAL dy = y1 - y0;
    COUNT(st, EVALUATED, 1);
    COUNT(st, LEVELS, 1);
    REAL u0 = 0, u1 = 1;
    int e0 = NO_EDGE, e1 = NO_EDGE;
    int ok = clipt(-dx, x0 - xmin, EDGE_LEFT, &u0, &e0, &u1, &e1, st)
             && clipt(dx, xmax - x0, EDGE_RIGHT, &u0, &e0, &u1, &e1, st)
             && clipt(-dy, y0 - ymin, EDGE_BOTTOM, &u0, &e0, &u1, &e1, st)
             && clipt(dy, ymax - y0, EDGE_TOP, &u0, &e0, &u1, &e1, st)
             && u0 <= u1;
    if (!ok) {
        COUNT(st, REJECTED, 1);
        return 0;
    }
    return baseline_piece(dx == 0 && dy == 0, x0, y0, x1, y1, u0, e0, u1, e1, xmin, ymin, xmax,
                          ymax, st, out);
}

/* The half-plane of edge `bit`, applied when `flags` has that bit (selects, no branches). */
void leaf_cut(int bit, int flags, REAL *u0, int *e0, REAL *u1, int *e1, REAL x0,
                     REAL y0, REAL x1, REAL y1, REAL xmin, REAL ymin, REAL xmax, REAL ymax) {
    REAL dx = x1 - x0, dy = y1 - y0, p, q;
    int edge;
    if (bit == LEFT) {
        p = -dx; q = x0 - xmin; edge = EDGE_LEFT;
    } else if (bit == RIGHT) {
        p = dx; q = xmax - x0; edge = EDGE_RIGHT;
    } else if (bit == BOTTOM) {
        p = -dy; q = y0 - ymin; edge = EDGE_BOTTOM;
    } else {
        p = dy; q = ymax - y0; edge = EDGE_TOP;
    }
    int on = (flags & bit) != 0;
    REAL r = q / (on ? p : (REAL)1);
    int enter = on && p < 0 && r > *u0;
    int leave = on && p > 0 && r < *u1;
    if (enter) { *u0 = r; *e0 = edge; }
    if (leave) { *u1 = r; *e1 = edge; }
}

int count_divisions(int flags) {
    return (flags & 1) + ((flags >> 1) & 1) + ((flags >> 2) & 1) + ((flags >> 3) & 1);
}

/* [u0, u1] cut by the flagged half-planes (left, right, bottom, top), e0 and e1 the edges
 * that cut it (else left as they are). */
void leaf_cuts(int flags, REAL *u0, int *e0, REAL *u1, int *e1, REAL x0, REAL y0, REAL x1,
               REAL y1, REAL xmin, REAL ymin, REAL xmax, REAL ymax) {
    leaf_cut(LEFT, flags, u0, e0, u1, e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(RIGHT, flags, u0, e0, u1, e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(BOTTOM, flags, u0, e0, u1, e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(TOP, flags, u0, e0, u1, e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
}

/* Clip the leaf [ta, tb] on the flagged half-planes; out = (u0, u1, ax, ay, bx, by). */
int liang_barsky_leaf(REAL x0, REAL y0, REAL x1, REAL y1, REAL ta, REAL tb, REAL xa,
                             REAL ya, REAL xb, REAL yb, int flags, REAL xmin, REAL ymin,
                             REAL xmax, REAL ymax, REAL *out) {
    REAL u0 = ta, u1 = tb;
    int e0 = NO_EDGE, e1 = NO_EDGE;
    leaf_cuts(flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    cut_piece(x0, y0, x1, y1, u0, e0, xa, ya, u1, e1, xb, yb, xmin, ymin, xmax, ymax, out);
    return u0 <= u1;
}

/* An undecided leaf [ta, tb] (ends a and b, `codes` their outcodes or'ed) clipped in
 * exact mode: counted, and cut on the edges of the unsure bits of `codes`. */
int clip_leaf(REAL x0, REAL y0, REAL x1, REAL y1, REAL ta, REAL tb, REAL xa, REAL ya,
              REAL xb, REAL yb, int codes, REAL xmin, REAL ymin, REAL xmax, REAL ymax,
              Counters st, REAL *out) {
    int flags = codes & UNSURE_BITS;
    COUNT(st, CLIPPED, 1);
    COUNT(st, INTERSECTIONS, count_divisions(flags));
    return liang_barsky_leaf(x0, y0, x1, y1, ta, tb, xa, ya, xb, yb, flags, xmin, ymin, xmax,
                             ymax, out);
}

/* --- baselines/cohen_sutherland.py -------------------------------------------------- */

REAL cs_edge_parameter(int code, REAL x0, REAL y0, REAL dx, REAL dy, REAL xmin,
                              REAL ymin, REAL xmax, REAL ymax, int *edge, int *bit) {
    if (code & TOP) {
        *edge = EDGE_TOP; *bit = TOP;
        return (ymax - y0) / dy;
    }
    if (code & BOTTOM) {
        *edge = EDGE_BOTTOM; *bit = BOTTOM;
        return (ymin - y0) / dy;
    }
    if (code & RIGHT) {
        *edge = EDGE_RIGHT; *bit = RIGHT;
        return (xmax - x0) / dx;
    }
    *edge = EDGE_LEFT; *bit = LEFT;
    return (xmin - x0) / dx;
}

/* One move of an outside end, (t, x, y) with outcode *code (`at_end`: the end at t1, else
 * the one at t0): onto the line of an edge it is beyond, if that moves it inward, else
 * that edge's bit is dropped from its outcode. */
void cs_move(int at_end, REAL *t, REAL *x, REAL *y, int *code, REAL x0, REAL y0, REAL x1,
             REAL y1, REAL dx, REAL dy, REAL xmin, REAL ymin, REAL xmax, REAL ymax) {
    int edge, bit;
    REAL t_edge = cs_edge_parameter(*code, x0, y0, dx, dy, xmin, ymin, xmax, ymax, &edge, &bit);
    if (at_end ? t_edge < *t : t_edge > *t) {
        *t = t_edge;
        *code = edge_point_code(x0, y0, x1, y1, edge, xmin, ymin, xmax, ymax, x, y);
    } else {
        *code &= ~bit;
    }
}

int cohen_sutherland_segment(REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin, REAL ymin,
                                    REAL xmax, REAL ymax, Counters st, REAL *out) {
    REAL dx = x1 - x0;
    REAL dy = y1 - y0;
    REAL t0 = 0, t1 = 1;
    REAL ax = x0, ay = y0, bx = x1, by = y1;
    int ca = outcode(ax, ay, xmin, ymin, xmax, ymax);
    int cb = outcode(bx, by, xmin, ymin, xmax, ymax);
    for (int move = 0; move < CS_MAX_MOVES; move++) {
        COUNT(st, EVALUATED, 1);
        COUNT(st, LEVELS, 1);
        if ((ca | cb) == 0) {
            COUNT(st, ACCEPTED, 1);
            set_piece(out, t0, t1, ax, ay, bx, by);
            return is_piece(dx == 0 && dy == 0, out);
        }
        if (ca & cb) {
            COUNT(st, REJECTED, 1);
            return 0;
        }
        COUNT(st, CLIPPED, 1);
        COUNT(st, INTERSECTIONS, 1);
        if (ca != 0)
            cs_move(0, &t0, &ax, &ay, &ca, x0, y0, x1, y1, dx, dy, xmin, ymin, xmax, ymax);
        else
            cs_move(1, &t1, &bx, &by, &cb, x0, y0, x1, y1, dx, dy, xmin, ymin, xmax, ymax);
        if (t0 > t1)
            return 0;
    }
    return 0;
}

/* --- baselines/nicholl_lee_nicholl.py ----------------------------------------------- */

int nln_extreme(REAL x, REAL y) {
    REAL ax = fabs(x), ay = fabs(y);
    return py_max(ax, ay) > NLN_BIG || (0 < ax && ax < NLN_SMALL) || (0 < ay && ay < NLN_SMALL);
}

void nln_normalized(REAL *x, REAL *y) {
    REAL m = py_max(fabs(*x), fabs(*y));
    if (m > 0) {
        *x = *x / m;
        *y = *y / m;
    }
}

int nln_turn(REAL ax, REAL ay, REAL bx, REAL by) {
    if (nln_extreme(ax, ay) || nln_extreme(bx, by)) {
        nln_normalized(&ax, &ay);
        nln_normalized(&bx, &by);
    }
    REAL c = ax * by - ay * bx;
    return c > 0 ? 1 : (c < 0 ? -1 : 0);
}

int nln_single_edge(int code) {
    if (code == LEFT) return EDGE_LEFT;
    if (code == RIGHT) return EDGE_RIGHT;
    if (code == BOTTOM) return EDGE_BOTTOM;
    return EDGE_TOP;
}

REAL nln_parameter(int edge, REAL px, REAL py, REAL ex, REAL ey, REAL left, REAL bottom,
                          REAL right, REAL top, Counters st) {
    COUNT(st, INTERSECTIONS, 1);
    if (edge == EDGE_LEFT) return (left - px) / ex;
    if (edge == EDGE_RIGHT) return (right - px) / ex;
    if (edge == EDGE_BOTTOM) return (bottom - py) / ey;
    return (top - py) / ey;
}

int nln_exit_from_inside(int c1, REAL px, REAL py, REAL ex, REAL ey, REAL left,
                                REAL bottom, REAL right, REAL top) {
    if (c1 == LEFT || c1 == RIGHT || c1 == BOTTOM || c1 == TOP)
        return nln_single_edge(c1);
    REAL cx = (c1 & RIGHT) ? right : left;
    REAL cy = (c1 & TOP) ? top : bottom;
    int ccw = nln_turn(cx - px, cy - py, ex, ey) > 0;
    if (c1 == (RIGHT | TOP)) return ccw ? EDGE_TOP : EDGE_RIGHT;
    if (c1 == (LEFT | TOP)) return ccw ? EDGE_LEFT : EDGE_TOP;
    if (c1 == (LEFT | BOTTOM)) return ccw ? EDGE_BOTTOM : EDGE_LEFT;
    return ccw ? EDGE_RIGHT : EDGE_BOTTOM;
}

int nln_exit_from_left(REAL px, REAL py, REAL ex, REAL ey, REAL bottom, REAL right,
                              REAL top) {
    if (nln_turn(right - px, top - py, ex, ey) > 0) return EDGE_TOP;
    if (nln_turn(right - px, bottom - py, ex, ey) < 0) return EDGE_BOTTOM;
    return EDGE_RIGHT;
}

int nln_canonical_clip(REAL px, REAL py, REAL qx, REAL qy, REAL left, REAL bottom,
                              REAL right, REAL top, Counters st, REAL *u0, int *e0, REAL *u1,
                              int *e1) {
    REAL ex = qx - px;
    REAL ey = qy - py;
    int c0 = outcode(px, py, left, bottom, right, top);
    int c1 = outcode(qx, qy, left, bottom, right, top);
    *u0 = 0; *e0 = NO_EDGE; *u1 = 1; *e1 = NO_EDGE;
    if (c0 == 0) {
        if (c1 == 0)
            return 1;
        *e1 = nln_exit_from_inside(c1, px, py, ex, ey, left, bottom, right, top);
        *u1 = py_min(nln_parameter(*e1, px, py, ex, ey, left, bottom, right, top, st), 1);
        return 1;
    }
    if (c1 & c0)
        return 0;
    if (c0 == LEFT) {
        if (nln_turn(left - px, bottom - py, ex, ey) < 0
            || nln_turn(ex, ey, left - px, top - py) < 0)
            return 0;
        *e0 = EDGE_LEFT;
    } else {
        if (c1 & (LEFT | BOTTOM))
            return 0;
        if (nln_turn(right - px, bottom - py, ex, ey) < 0
            || nln_turn(ex, ey, left - px, top - py) < 0)
            return 0;
        *e0 = nln_turn(left - px, bottom - py, ex, ey) >= 0 ? EDGE_LEFT : EDGE_BOTTOM;
    }
    REAL t0 = nln_parameter(*e0, px, py, ex, ey, left, bottom, right, top, st);
    if (c1 == 0) {
        *u0 = py_max(t0, 0);
        return 1;
    }
    *e1 = nln_exit_from_left(px, py, ex, ey, bottom, right, top);
    *u1 = py_min(nln_parameter(*e1, px, py, ex, ey, left, bottom, right, top, st), 1);
    *u0 = py_max(t0, 0);
    return t0 <= *u1;
}

int nln_original_edge(int edge, int flip_x, int flip_y, int swap) {
    if (edge == NO_EDGE) return NO_EDGE;
    if (swap) edge ^= 2;
    if (flip_x && edge < EDGE_BOTTOM) edge ^= 1;
    if (flip_y && edge >= EDGE_BOTTOM) edge ^= 1;
    return edge;
}

int nicholl_lee_nicholl_segment(REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin,
                                       REAL ymin, REAL xmax, REAL ymax, Counters st,
                                       REAL *out) {
    REAL dx = x1 - x0;
    REAL dy = y1 - y0;
    COUNT(st, EVALUATED, 1);
    COUNT(st, LEVELS, 1);
    int c0 = outcode(x0, y0, xmin, ymin, xmax, ymax);
    if (dx == 0 && dy == 0) {
        if (c0 == 0) {
            COUNT(st, ACCEPTED, 1);
            set_piece(out, 0, 1, x0, y0, x1, y1);
            return 1;
        }
        COUNT(st, REJECTED, 1);
        return 0;
    }
    int flip_x = (c0 & RIGHT) != 0;
    int flip_y = (c0 & TOP) != 0;
    REAL px = x0, qx = x1, left = xmin, right = xmax;
    REAL py = y0, qy = y1, bottom = ymin, top = ymax;
    if (flip_x) {
        px = -x0; qx = -x1; left = -xmax; right = -xmin;
    }
    if (flip_y) {
        py = -y0; qy = -y1; bottom = -ymax; top = -ymin;
    }
    int swap = (c0 & (LEFT | RIGHT)) == 0 && (c0 & (BOTTOM | TOP)) != 0;
    if (swap) {
        REAL tmp = px; px = py; py = tmp;
        tmp = qx; qx = qy; qy = tmp;
        tmp = left; left = bottom; bottom = tmp;
        tmp = right; right = top; top = tmp;
    }
    REAL u0, u1;
    int e0, e1;
    if (!nln_canonical_clip(px, py, qx, qy, left, bottom, right, top, st, &u0, &e0, &u1, &e1)) {
        COUNT(st, REJECTED, 1);
        return 0;
    }
    e0 = nln_original_edge(e0, flip_x, flip_y, swap);
    e1 = nln_original_edge(e1, flip_x, flip_y, swap);
    return baseline_piece(0, x0, y0, x1, y1, u0, e0, u1, e1, xmin, ymin, xmax, ymax, st, out);
}

/* --- baselines/midpoint.py ---------------------------------------------------------- */

/* A search's final bracket: b[0..3] = (a, xa, ya, ca), b[4..7] = (b, xb, yb, cb). */
typedef struct {
    REAL a, xa, ya;
    int ca;
    REAL b, xb, yb;
    int cb;
    int level;
} Bracket;

Bracket midpoint_search(REAL x0, REAL y0, REAL dx, REAL dy, REAL x1, REAL y1, int c0,
                               int c1, REAL length, int toward_end, int max_depth, REAL tol,
                               int exact, REAL xmin, REAL ymin, REAL xmax, REAL ymax,
                               Counters st) {
    REAL dx_err, dy_err;
    difference_dd(x1, x0, &dx_err);
    difference_dd(y1, y0, &dy_err);
    REAL a = 0, xa = x0, ya = y0;
    int ca = c0;
    REAL b = 1, xb = x1, yb = y1;
    int cb = c1;
    REAL st_t, st_x, st_y;
    int st_c;
    if (toward_end) {
        st_t = a; st_x = xa; st_y = ya; st_c = ca;
    } else {
        st_t = b; st_x = xb; st_y = yb; st_c = cb;
    }
    int found = 0;
    int level = 0;
    while (level < max_depth && (b - a) * length > tol) {
        REAL m = a + (b - a) * 1 / 2;
        REAL xm, ym, cx, mx, cy, my;
        interpolated_point(x0, y0, dx, dx_err, dy, dy_err, m, &xm, &ym, &cx, &mx, &cy, &my);
        int cm = wide_outcode(xm, ym, cx, mx, cy, my, xmin, ymin, xmax, ymax);
        xm += cx;
        ym += cy;
        level += 1;
        COUNT(st, EVALUATED, 1);
        int far_ = toward_end ? cb : ca;
        if ((cm & far_) >> SURE_SHIFT) {
            COUNT(st, REJECTED, 1);
            COUNT(st, LEVELS + level, 1);
            if (toward_end) {
                b = m; xb = xm; yb = ym; cb = cm;
            } else {
                a = m; xa = xm; ya = ym; ca = cm;
            }
        } else {
            COUNT(st, SUBDIVIDED, 1);
            if (toward_end) {
                a = m; xa = xm; ya = ym; ca = cm;
            } else {
                b = m; xb = xm; yb = ym; cb = cm;
            }
            if ((cm & UNSURE_BITS) == 0) {
                st_t = m; st_x = xm; st_y = ym; st_c = cm;
                found = 1;
            }
        }
    }
    atomic_max(&st[DEEPEST], level);
    REAL near_t = toward_end ? a : b;
    int near_c = toward_end ? ca : cb;
    if (!found && (near_c >> SURE_SHIFT) == 0 && near_t != st_t) {
        REAL lo = py_min(near_t, st_t);
        REAL hi = py_max(near_t, st_t);
        REAL h = lo + (hi - lo) * 1 / 2;
        REAL hx, hy, cx, mx, cy, my;
        interpolated_point(x0, y0, dx, dx_err, dy, dy_err, h, &hx, &hy, &cx, &mx, &cy, &my);
        found = (wide_outcode(hx, hy, cx, mx, cy, my, xmin, ymin, xmax, ymax) & UNSURE_BITS) == 0;
    }
    if (toward_end) {
        if (exact || !(found && (ca >> SURE_SHIFT) == 0)) {
            a = st_t; xa = st_x; ya = st_y; ca = st_c;
        } else {
            ca = 0;
        }
    } else {
        if (exact || !(found && (cb >> SURE_SHIFT) == 0)) {
            b = st_t; xb = st_x; yb = st_y; cb = st_c;
        } else {
            cb = 0;
        }
    }
    Bracket r = {a, xa, ya, ca, b, xb, yb, cb, level};
    return r;
}

/* A bracket whose only visible part is an end inside the window: out = that end, as a
   zero-length piece; 0 if neither end is inside. */
int inside_end_only(Bracket k, REAL *out) {
    if (k.ca == 0) {
        set_piece(out, k.a, k.a, k.xa, k.ya, k.xa, k.ya);
        return 1;
    }
    if (k.cb == 0) {
        set_piece(out, k.b, k.b, k.xb, k.yb, k.xb, k.yb);
        return 1;
    }
    return 0;
}

/* Decide a final bracket; out = (u0, u1, ax, ay, bx, by) of its visible part. */
int midpoint_leaf(REAL x0, REAL y0, REAL x1, REAL y1, Bracket k, int exact, REAL xmin,
                         REAL ymin, REAL xmax, REAL ymax, Counters st, REAL *out) {
    COUNT(st, EVALUATED, 1);
    COUNT(st, LEVELS + k.level, 1);
    if ((k.ca & k.cb) >> SURE_SHIFT) {
        COUNT(st, REJECTED, 1);
        return 0;
    }
    if ((k.ca | k.cb) == 0) {
        COUNT(st, ACCEPTED, 1);
        set_piece(out, k.a, k.b, k.xa, k.ya, k.xb, k.yb);
        return 1;
    }
    if (!exact) {
        COUNT(st, DROPPED, 1);
        return inside_end_only(k, out);
    }
    if (!clip_leaf(x0, y0, x1, y1, k.a, k.b, k.xa, k.ya, k.xb, k.yb, k.ca | k.cb, xmin, ymin,
                   xmax, ymax, st, out))
        return inside_end_only(k, out);
    return 1;
}

/* The visible part's end on one side of a segment whose end there is outside (`at_end`:
 * the end at t = 1, else t = 0), searched from the other end: its (t, x, y) in *t, *x, *y;
 * 0 if nothing is visible. */
int midpoint_end(int at_end, REAL x0, REAL y0, REAL dx, REAL dy, REAL x1, REAL y1, int c0,
                 int c1, REAL length, int max_depth, REAL tol, int exact, REAL xmin,
                 REAL ymin, REAL xmax, REAL ymax, Counters st, REAL *t, REAL *x, REAL *y) {
    Bracket k = midpoint_search(x0, y0, dx, dy, x1, y1, wide(c0), wide(c1), length, at_end,
                                max_depth, tol, exact, xmin, ymin, xmax, ymax, st);
    REAL leaf[6];
    if (!midpoint_leaf(x0, y0, x1, y1, k, exact, xmin, ymin, xmax, ymax, st, leaf))
        return 0;
    *t = leaf[at_end];
    *x = leaf[2 + 2 * at_end];
    *y = leaf[3 + 2 * at_end];
    return 1;
}

int midpoint_segment(REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin, REAL ymin,
                            REAL xmax, REAL ymax, int max_depth, REAL tol, int exact,
                            Counters st, REAL *out) {
    REAL dx = x1 - x0;
    REAL dy = y1 - y0;
    REAL length = hypot(dx, dy);
    int c0 = outcode(x0, y0, xmin, ymin, xmax, ymax);
    int c1 = outcode(x1, y1, xmin, ymin, xmax, ymax);
    if ((c0 | c1) == 0 || (c0 & c1) || max_depth == 0 || length <= tol) {
        Bracket whole = {0, x0, y0, wide(c0), 1, x1, y1, wide(c1), 0};
        int ok = midpoint_leaf(x0, y0, x1, y1, whole, exact, xmin, ymin, xmax, ymax, st, out);
        if (!ok || (!exact && out[0] == out[1] && (c0 | c1) != 0))
            return 0;
        return is_piece(dx == 0 && dy == 0, out);
    }
    COUNT(st, EVALUATED, 1);
    COUNT(st, SUBDIVIDED, 1);
    set_piece(out, 0, 1, x0, y0, x1, y1);
    if (c1 != 0 && !midpoint_end(1, x0, y0, dx, dy, x1, y1, c0, c1, length, max_depth, tol,
                                 exact, xmin, ymin, xmax, ymax, st, &out[1], &out[4], &out[5]))
        return 0;
    if (c0 != 0 && !midpoint_end(0, x0, y0, dx, dy, x1, y1, c0, c1, length, max_depth, tol,
                                 exact, xmin, ymin, xmax, ymax, st, &out[0], &out[2], &out[3]))
        return 0;
    return is_piece(0, out);
}

/* --- kernels/segments.py: RNSCA ----------------------------------------------------- */

int auto_n(REAL piece_length, REAL tol, int levels_left) {
    if (!(piece_length > tol * pown((REAL)2, levels_left)))
        return AUTO_N_BASE;
    REAL k = pow(piece_length / tol, (REAL)1 / levels_left);
    return !(k < N_MAX) ? N_MAX : max(AUTO_N_BASE, (int)ceil(k));
}

/* The RNSCA stack, one per work-item: floats (ta, tb, xa, ya, xb, yb), ints (ca, cb, level). */
typedef struct {
    REAL f[STACK_CAPACITY][6];
    int i[STACK_CAPACITY][3];
} Stack;

void stack_push(Stack *stack, int sp, REAL ta, REAL tb, REAL xa, REAL ya, REAL xb, REAL yb,
                int ca, int cb, int level) {
    set_piece(stack->f[sp], ta, tb, xa, ya, xb, yb);
    stack->i[sp][0] = ca;
    stack->i[sp][1] = cb;
    stack->i[sp][2] = level;
}

/* A segment that its outcodes decide at level 0 ((c0 | c1) == 0: accepted, out = the
 * segment; c0 & c1: rejected), counted; returns kept. */
int rnsca_decided(REAL x0, REAL y0, REAL x1, REAL y1, int c0, int c1, Counters st,
                  REAL *out) {
    COUNT(st, EVALUATED, 1);
    COUNT(st, LEVELS, 1);
    if (c0 & c1) {
        COUNT(st, REJECTED, 1);
        return 0;
    }
    COUNT(st, ACCEPTED, 1);
    set_piece(out, 0, 1, x0, y0, x1, y1);
    return 1;
}

int rnsca_segment(REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin, REAL ymin, REAL xmax,
                         REAL ymax, int n_fixed, int max_depth, REAL tol,
                         int exact, Counters st, Stack *stack, REAL *out) {
    REAL dx = x1 - x0;
    REAL dy = y1 - y0;
    int c0 = outcode(x0, y0, xmin, ymin, xmax, ymax);
    int c1 = outcode(x1, y1, xmin, ymin, xmax, ymax);
    if ((c0 | c1) == 0 || (c0 & c1))
        return rnsca_decided(x0, y0, x1, y1, c0, c1, st, out);
    REAL length = hypot(dx, dy);
    if (max_depth == 0 || length <= tol) {
        COUNT(st, EVALUATED, 1);
        COUNT(st, LEVELS, 1);
        if (!exact) {
            COUNT(st, DROPPED, 1);
            return 0;
        }
        return clip_leaf(x0, y0, x1, y1, 0, 1, x0, y0, x1, y1, c0 | c1, xmin, ymin, xmax, ymax,
                         st, out)
               && is_piece(0, out);
    }
    /* The merged interval [lo, hi] of the clipped leaves and accepted children. */
    REAL lo_t = INF_REAL, lo_x = 0, lo_y = 0;
    REAL hi_t = -INF_REAL, hi_x = 0, hi_y = 0;
    REAL leaf[6];
    COUNT(st, EVALUATED, 1);
    COUNT(st, SUBDIVIDED, 1);
    stack_push(stack, 0, 0, 1, x0, y0, x1, y1, wide(c0), wide(c1), 0);
    REAL dx_err, dy_err;
    difference_dd(x1, x0, &dx_err);
    difference_dd(y1, y0, &dy_err);
    int sp = 1;
    while (sp > 0) {
        sp -= 1;
        REAL ta = stack->f[sp][0];
        REAL tb = stack->f[sp][1];
        REAL xb = stack->f[sp][4];
        REAL yb = stack->f[sp][5];
        int cb = stack->i[sp][1];
        int level = stack->i[sp][2] + 1;
        REAL step = tb - ta;
        int n = n_fixed > 0 ? n_fixed : auto_n(step * length, tol, max_depth - level + 1);
        REAL pt = ta;
        REAL px = stack->f[sp][2];
        REAL py = stack->f[sp][3];
        int pc = stack->i[sp][0];
        atomic_max(&st[DEEPEST], level);
        for (int j = 1; j <= n; j++) {
            REAL t, x, y;
            int c;
            if (j == n) {
                t = tb; x = xb; y = yb; c = cb;
            } else {
                t = ta + step * (REAL)j / (REAL)n;
                REAL cx, mx, cy, my;
                interpolated_point(x0, y0, dx, dx_err, dy, dy_err, t, &x, &y, &cx, &mx, &cy,
                                   &my);
                c = wide_outcode(x, y, cx, mx, cy, my, xmin, ymin, xmax, ymax);
                x += cx;
                y += cy;
            }
            COUNT(st, EVALUATED, 1);
            if ((pc | c) == 0) {
                COUNT(st, ACCEPTED, 1);
                COUNT(st, LEVELS + level, 1);
                if (pt < t && pt < lo_t) {
                    lo_t = pt; lo_x = px; lo_y = py;
                }
                if (pt < t && t > hi_t) {
                    hi_t = t; hi_x = x; hi_y = y;
                }
            } else if ((pc & c) >> SURE_SHIFT) {
                COUNT(st, REJECTED, 1);
                COUNT(st, LEVELS + level, 1);
            } else if (level >= max_depth || (t - pt) * length <= tol || pc == c
                       || sp >= STACK_CAPACITY) {
                COUNT(st, LEVELS + level, 1);
                if (!exact) {
                    COUNT(st, DROPPED, 1);
                } else if (clip_leaf(x0, y0, x1, y1, pt, t, px, py, x, y, pc | c, xmin, ymin,
                                     xmax, ymax, st, leaf)
                           && is_piece(0, leaf)) {
                    if (leaf[0] < lo_t) {
                        lo_t = leaf[0]; lo_x = leaf[2]; lo_y = leaf[3];
                    }
                    if (leaf[1] > hi_t) {
                        hi_t = leaf[1]; hi_x = leaf[4]; hi_y = leaf[5];
                    }
                }
            } else {
                COUNT(st, SUBDIVIDED, 1);
                stack_push(stack, sp, pt, t, px, py, x, y, pc, c, level);
                sp += 1;
            }
            pt = t; px = x; py = y; pc = c;
        }
    }
    if (!(lo_t <= hi_t))
        return 0;
    set_piece(out, lo_t, hi_t, lo_x, lo_y, hi_x, hi_y);
    return is_piece(0, out);
}

/* RNSCA's level 0 as the Numba block driver runs it (`_rnsca_block`): a segment that is
 * accepted, rejected, or a leaf (short, or max_depth 0) is decided here; only the
 * others go through the depth-first `rnsca_segment`. Same pieces, same counters. The
 * decided ones take one path, without branches up to the end points: the half-planes of
 * the clipped ones' flags (none for the others) are applied to every segment. */
int rnsca_level0(REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin, REAL ymin, REAL xmax,
                        REAL ymax, int n_fixed, int max_depth, REAL tol,
                        int exact, Counters st, Stack *stack, REAL *out) {
    int c0 = outcode(x0, y0, xmin, ymin, xmax, ymax);
    int c1 = outcode(x1, y1, xmin, ymin, xmax, ymax);
    int reject = (c0 & c1) != 0;
    int amb = !reject && (c0 | c1) != 0;
    int split = amb && max_depth > 0 && (fabs(x1 - x0) + fabs(y1 - y0) > tol);
    if (split)
        return rnsca_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed, max_depth, tol,
                             exact, st, stack, out);
    int clip = amb && exact;
    int flags = clip ? (c0 | c1) : 0;
    COUNT(st, EVALUATED, 1);
    COUNT(st, LEVELS, 1);
    if (!reject && !amb) COUNT(st, ACCEPTED, 1);
    if (reject) COUNT(st, REJECTED, 1);
    if (clip) COUNT(st, CLIPPED, 1);
    if (amb && !exact) COUNT(st, DROPPED, 1);
    COUNT(st, INTERSECTIONS, count_divisions(flags));
    REAL u0 = 0, u1 = 1;
    int e0 = NO_EDGE, e1 = NO_EDGE;
    leaf_cuts(flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    if (reject || (amb && !exact))
        return 0;
    cut_piece(x0, y0, x1, y1, u0, e0, x0, y0, u1, e1, x1, y1, xmin, ymin, xmax, ymax, out);
    return u0 <= u1 && is_piece(x0 == x1 && y0 == y1, out);
}

/* --- kernels --------------------------------------------------------------------------- */

/* A work-group's counters (the `width` of its row): zeroed before its work-items count,
 * summed in local memory, written once to its row of `counters` after. Every work-item
 * of the group calls both (they hold barriers). */
void clear_counters(Counters st, int width) {
    for (int k = get_local_id(0); k < width; k += LOCAL_SIZE)
        st[k] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
}

void store_counters(Counters st, int width, __global long *counters) {
    barrier(CLK_LOCAL_MEM_FENCE);
    __global long *row = counters + get_group_id(0) * width;
    for (int k = get_local_id(0); k < width; k += LOCAL_SIZE)
        row[k] = st[k];
}

/* The group's smallest `my_bad` (each work-item's first item that is not finite) into
 * first_bad[group]: a tree reduction in `bad`, local memory of LOCAL_SIZE entries. */
void store_first_bad(__local long *bad, long my_bad, __global long *first_bad) {
    int l = get_local_id(0);
    bad[l] = my_bad;
    for (int step = LOCAL_SIZE / 2; step > 0; step /= 2) {
        barrier(CLK_LOCAL_MEM_FENCE);
        if (l < step)
            bad[l] = min(bad[l], bad[l + step]);
    }
    if (l == 0)
        first_bad[get_group_id(0)] = bad[0];
}

/* Pass 1 over `n` items, each a segment (`pairs` 0: item i is segment i, clipped to
 * window 0) or a (segment, window) pair (`pairs` 1: item i is pair p = item_base + i,
 * segment pair_segment[p] clipped to window pair_window[p]). Item i's result (t0, t1, ax, ay, bx, by) goes to
 * result[6 i] and keep[i] in {0, 1}. A grid-stride loop: the host launches few groups
 * (`_groups`), so each group's counter row sums many items and few rows are written and
 * reduced (`reduce_counters`). A segment that is not finite (a NaN or infinite
 * coordinate, or differences that overflow: `check_segment_values`) is not clipped;
 * the smallest such item of the group goes to first_bad[group] (n if none). */
__kernel __attribute__((reqd_work_group_size(LOCAL_SIZE, 1, 1)))
void clip_segments(__global const REAL *segments, const long n,
                   __global const REAL *windows, const int pairs, const long item_base,
                   __global const long *pair_segment, __global const int *pair_window,
                   const int method, const int n_fixed, const int max_depth, const REAL tol,
                   const int exact, __global REAL *result, __global long *keep,
                   __global long *counters, __global long *first_bad) {
    __local int st[SEGMENT_COUNTERS];
    __local long bad[LOCAL_SIZE];
    clear_counters(st, SEGMENT_COUNTERS);
    long my_bad = n;  /* this work-item's first item that is not finite */
    long stride = get_global_size(0);
    for (long i = get_global_id(0); i < n; i += stride) {
        long s = pairs ? pair_segment[item_base + i] : i;
        __global const REAL *w = windows + 4 * (pairs ? pair_window[item_base + i] : 0);
        REAL xmin = w[0], ymin = w[1], xmax = w[2], ymax = w[3];
        REAL x0 = segments[4 * s], y0 = segments[4 * s + 1];
        REAL x1 = segments[4 * s + 2], y1 = segments[4 * s + 3];
        REAL out[6];
        int kept = 0;
        if (!(isfinite(x0) && isfinite(y0) && isfinite(x1) && isfinite(y1)
              && isfinite(x1 - x0) && isfinite(y1 - y0))) {
            if (my_bad == n)  /* a work-item's items rise: its first is its smallest */
                my_bad = i;
        } else if (method == RNSCA) {
            Stack stack;
            kept = rnsca_level0(x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed, max_depth,
                                tol, exact, st, &stack, out);
        } else if (method == COHEN_SUTHERLAND) {
            kept = cohen_sutherland_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st, out);
        } else if (method == LIANG_BARSKY) {
            kept = liang_barsky_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st, out);
        } else if (method == NICHOLL_LEE_NICHOLL) {
            kept = nicholl_lee_nicholl_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st, out);
        } else {
            kept = midpoint_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, max_depth, tol,
                                    exact, st, out);
        }
        keep[i] = kept;
        if (kept)
            for (int k = 0; k < 6; k++)
                result[6 * i + k] = out[k];
    }
    store_counters(st, SEGMENT_COUNTERS, counters);
    store_first_bad(bad, my_bad, first_bad);
}

/* Pass 3: copy item i's kept result to slot position[i] - 1 (`position` is the
 * inclusive prefix sum of `keep`), its ends clamped into its window (`_write_piece`);
 * its segment to `source` and its parameters to `t` where asked for (`want_source`,
 * `want_t`), and for pairs its window to `window_out`. */
__kernel void write_pieces(__global const REAL *result, __global const long *keep,
                           __global const long *position, const long n,
                           __global const REAL *windows, const int pairs,
                           const long item_base, __global const long *pair_segment,
                           __global const int *pair_window, const long segment_base, const int want_source, const int want_t,
                           __global REAL *pieces, __global long *source, __global REAL *t,
                           __global int *window_out) {
    long i = get_global_id(0);
    if (i >= n || !keep[i])
        return;
    long k = position[i] - 1;
    int wi = pairs ? pair_window[item_base + i] : 0;
    __global const REAL *w = windows + 4 * wi;
    __global const REAL *r = result + 6 * i;
    pieces[4 * k] = clamp_real(r[2], w[0], w[2]);
    pieces[4 * k + 1] = clamp_real(r[3], w[1], w[3]);
    pieces[4 * k + 2] = clamp_real(r[4], w[0], w[2]);
    pieces[4 * k + 3] = clamp_real(r[5], w[1], w[3]);
    if (want_source)
        source[k] = pairs ? pair_segment[item_base + i] : segment_base + i;
    if (want_t) {
        t[2 * k] = r[0];
        t[2 * k + 1] = r[1];
    }
    if (pairs)
        window_out[k] = wi;
}

/* The counter rows of `rows` groups (each SEGMENT_COUNTERS wide) to one row: group k
 * (of SEGMENT_COUNTERS + 1) reduces column k, summed except DEEPEST (a maximum); the
 * last group takes the minimum of first_bad. Group 0 also copies the count of kept
 * items (the prefix sum's last value) to total[SEGMENT_COUNTERS + 1]: the host reads
 * one row back per chunk. */
__kernel __attribute__((reqd_work_group_size(LOCAL_SIZE, 1, 1)))
void reduce_counters(__global const long *counters, __global const long *first_bad,
                     const long rows, __global const long *position, const long n,
                     __global long *total) {
    __local long part[LOCAL_SIZE];
    int k = get_group_id(0);
    int l = get_local_id(0);
    int bad = k == SEGMENT_COUNTERS;
    long acc = bad ? LONG_MAX : 0;
    for (long r = l; r < rows; r += LOCAL_SIZE) {
        long v = bad ? first_bad[r] : counters[r * SEGMENT_COUNTERS + k];
        acc = bad ? min(acc, v) : (k == DEEPEST ? max(acc, v) : acc + v);
    }
    part[l] = acc;
    for (int step = LOCAL_SIZE / 2; step > 0; step /= 2) {
        barrier(CLK_LOCAL_MEM_FENCE);
        if (l < step) {
            long a = part[l], b = part[l + step];
            part[l] = bad ? min(a, b) : (k == DEEPEST ? max(a, b) : a + b);
        }
    }
    if (l == 0)
        total[k] = part[0];
    if (k == 0 && l == 0)
        total[SEGMENT_COUNTERS + 1] = n > 0 ? position[n - 1] : 0;
}

/* --- kernels/polylines.py: run-level pruning of lines ------------------------------- */
/* Lines are cut into chunks of RUN_LEAF_SEGMENTS segments. `chunk_boxes` stores each
 * chunk's bounding box; `classify_runs` runs RNSCA on runs of chunks (one work-item per
 * part: `clip_chains`' run stack) and stores each chunk's decision, and how many of its
 * segments must be clipped one by one; `clip_chunk_segments` clips those (one work-item
 * per chunk: `_clip_segments`). The chains are assembled on the host from the decisions
 * and the pieces (rnsca.kernels.polylines.assemble_line_blocks). The run stack's
 * RUN_STACK_CAPACITY entries (rnsca/constants.py says why) hold the deepest stack of any
 * part, for every N <= N_MAX; a run that would overflow it is clipped segment by
 * segment instead, as in Numba's kernel. */

long chunk_count(long first, long last) {
    return last <= first ? 0 : (last - first + RUN_LEAF_SEGMENTS - 1) / RUN_LEAF_SEGMENTS;
}

/* Chunk k: its part p = chunk_part[k], whose vertices are first..last, and its segments
 * a..b-1 (vertices a..b). */
typedef struct {
    long p, first, last, a, b;
} Chunk;

Chunk chunk_at(long k, __global const long *part_offsets, __global const long *chunk_start,
               __global const long *chunk_part) {
    Chunk c;
    c.p = chunk_part[k];
    c.first = part_offsets[c.p];
    c.last = part_offsets[c.p + 1] - 1;
    c.a = c.first + (k - chunk_start[c.p]) * RUN_LEAF_SEGMENTS;
    c.b = min(c.a + RUN_LEAF_SEGMENTS, c.last);
    return c;
}

/* Chunk k (of part chunk_part[k]): the box of its vertices, [xmin, ymin, xmax, ymax]. */
__kernel void chunk_boxes(__global const REAL *xy, __global const long *part_offsets,
                          __global const long *chunk_start, __global const long *chunk_part,
                          const long n_chunks, __global REAL *boxes) {
    long k = get_global_id(0);
    if (k >= n_chunks)
        return;
    Chunk c = chunk_at(k, part_offsets, chunk_start, chunk_part);
    Box box = point_box(xy[2 * c.a], xy[2 * c.a + 1]);
    for (long i = c.a + 1; i <= c.b; i++)
        box = box_union(box, point_box(xy[2 * i], xy[2 * i + 1]));
    boxes[4 * k] = box.xmin;
    boxes[4 * k + 1] = box.ymin;
    boxes[4 * k + 2] = box.xmax;
    boxes[4 * k + 3] = box.ymax;
}

void mark_chunks(__global uchar *decision, __global long *segmented, long chunk0,
                        long ca, long cb, uchar d, long first, long last) {
    for (long k = ca; k < cb; k++) {
        long a = first + k * RUN_LEAF_SEGMENTS;
        decision[chunk0 + k] = d;
        segmented[chunk0 + k] = d == CHUNK_SEGMENTED ? min(a + RUN_LEAF_SEGMENTS, last) - a : 0;
    }
}

/* Part p: RNSCA over runs of chunks (`clip_chains`); without `prune` (the baselines)
 * every chunk is clipped segment by segment. A part not `active` (unless `all_active`:
 * a ring of a polygon its shell's box decided) is skipped and not counted. */
__kernel __attribute__((reqd_work_group_size(LOCAL_SIZE, 1, 1)))
void classify_runs(__global const REAL *boxes, __global const long *part_offsets,
                   __global const long *chunk_start, __global const long *part_window,
                   __global const REAL *windows, const long n_parts, const int n_runs,
                   const int drop_edge_runs, const int prune, __global const uchar *active,
                   const int all_active, __global uchar *decision, __global long *segmented,
                   __global long *counters) {
    __local int st[COUNTERS_WIDTH];
    clear_counters(st, COUNTERS_WIDTH);
    long p = get_global_id(0);
    if (p < n_parts) {
        long first = part_offsets[p];
        long last = part_offsets[p + 1] - 1;
        long chunk0 = chunk_start[p];
        int chunks = (int)chunk_count(first, last);
        Box w = box_at(windows + 4 * part_window[p]);
        if (!all_active && !active[p]) {
            mark_chunks(decision, segmented, chunk0, 0, chunks, CHUNK_REJECTED, first, last);
        } else if (!prune) {
            mark_chunks(decision, segmented, chunk0, 0, chunks, CHUNK_SEGMENTED, first, last);
        } else if (chunks > 0) {
            int stack[RUN_STACK_CAPACITY][2];
            uchar levels[RUN_STACK_CAPACITY];
            stack[0][0] = 0;
            stack[0][1] = chunks;
            levels[0] = 0;
            int sp = 1;
            while (sp > 0) {
                sp -= 1;
                int ca = stack[sp][0], cb = stack[sp][1];
                int level = levels[sp];
                long a = first + (long)ca * RUN_LEAF_SEGMENTS;
                long b = min(first + (long)cb * RUN_LEAF_SEGMENTS, last);
                int slot = level >= N_LEVELS ? N_LEVELS - 1 : level;
                atomic_max(&st[RUN_DEEPEST], level);
                COUNT(st, RUNS_EVALUATED, 1);
                Box box = box_at(boxes + 4 * (chunk0 + ca));
                for (long k = chunk0 + ca + 1; k < chunk0 + cb; k++)
                    box = box_union(box, box_at(boxes + 4 * k));
                int strict = box.xmin > w.xmin && box.xmax < w.xmax && box.ymin > w.ymin
                             && box.ymax < w.ymax;
                int lo = box_outcode(box.xmin, box.ymin, w);
                int hi = box_outcode(box.xmax, box.ymax, w);
                uchar d;
                int runs;
                if ((lo | hi) == 0 && (strict || !drop_edge_runs)) {
                    d = CHUNK_ACCEPTED;
                    runs = RUNS_ACCEPTED;
                } else if (lo & hi) {
                    d = CHUNK_REJECTED;
                    runs = RUNS_REJECTED;
                } else if (cb - ca <= 1 || sp + n_runs > RUN_STACK_CAPACITY) {
                    d = CHUNK_SEGMENTED;
                    runs = RUNS_SEGMENTED;
                } else {
                    COUNT(st, RUNS_SUBDIVIDED, 1);
                    int k = min(n_runs, cb - ca);
                    for (int j = k; j > 0; j--) {
                        stack[sp][0] = ca + (int)((long)(cb - ca) * (j - 1) / k);
                        stack[sp][1] = ca + (int)((long)(cb - ca) * j / k);
                        levels[sp] = (uchar)(level + 1);
                        sp += 1;
                    }
                    continue;
                }
                COUNT(st, runs, 1);
                COUNT(st, RUN_LEVELS + slot, 1);
                COUNT(st, SEGMENT_LEVELS + slot, b - a);
                mark_chunks(decision, segmented, chunk0, ca, cb, d, first, last);
            }
        }
    }
    store_counters(st, COUNTERS_WIDTH, counters);
}

/* Chunk k, if it is to be clipped segment by segment: clip each of its segments
 * (`_clip_segments`: RNSCA's level 0 inline, then `rnsca_segment`, or the baseline) and
 * store keep and (t0, t1, ax, ay, bx, by) from slot position[k] - segmented[k] on. */
__kernel __attribute__((reqd_work_group_size(LOCAL_SIZE, 1, 1)))
void clip_chunk_segments(__global const REAL *xy, __global const long *part_offsets,
                         __global const long *chunk_start, __global const long *chunk_part,
                         __global const long *part_window, __global const REAL *windows,
                         const long n_chunks, __global const uchar *decision,
                         __global const long *segmented, __global const long *position,
                         const int method, const int n_fixed, const int max_depth,
                         const REAL tol, const int exact,
                         __global uchar *keep, __global REAL *result,
                         __global long *counters) {
    __local int st[COUNTERS_WIDTH];
    clear_counters(st, COUNTERS_WIDTH);
    long k = get_global_id(0);
    if (k < n_chunks && decision[k] == CHUNK_SEGMENTED) {
        Chunk c = chunk_at(k, part_offsets, chunk_start, chunk_part);
        long slot = position[k] - segmented[k];
        Box w = box_at(windows + 4 * part_window[c.p]);
        Stack stack;
        for (long i = c.a; i < c.b; i++, slot++) {
            REAL x0 = xy[2 * i], y0 = xy[2 * i + 1], x1 = xy[2 * i + 2], y1 = xy[2 * i + 3];
            REAL out[6];
            int kept;
            if (method == RNSCA) {
                int c0 = outcode(x0, y0, w.xmin, w.ymin, w.xmax, w.ymax);
                int c1 = outcode(x1, y1, w.xmin, w.ymin, w.xmax, w.ymax);
                if ((c0 | c1) == 0 || (c0 & c1))
                    kept = rnsca_decided(x0, y0, x1, y1, c0, c1, st, out);
                else
                    kept = rnsca_segment(x0, y0, x1, y1, w.xmin, w.ymin, w.xmax, w.ymax,
                                         n_fixed, max_depth, tol, exact, st, &stack,
                                         out);
            } else if (method == COHEN_SUTHERLAND) {
                kept = cohen_sutherland_segment(x0, y0, x1, y1, w.xmin, w.ymin, w.xmax, w.ymax,
                                                st, out);
            } else if (method == LIANG_BARSKY) {
                kept = liang_barsky_segment(x0, y0, x1, y1, w.xmin, w.ymin, w.xmax, w.ymax, st,
                                            out);
            } else if (method == NICHOLL_LEE_NICHOLL) {
                kept = nicholl_lee_nicholl_segment(x0, y0, x1, y1, w.xmin, w.ymin, w.xmax,
                                                   w.ymax, st, out);
            } else {
                kept = midpoint_segment(x0, y0, x1, y1, w.xmin, w.ymin, w.xmax, w.ymax,
                                        max_depth, tol, exact, st, out);
            }
            keep[slot] = (uchar)kept;
            for (int j = 0; j < 6; j++)
                result[6 * slot + j] = kept ? out[j] : 0;
        }
    }
    store_counters(st, COUNTERS_WIDTH, counters);
}

/* --- bezier.py: classification and flattening of Bézier segments ------------------ */

/* Segment classes (SEGMENT_*): by the outcodes of the control points, all inside, all
 * beyond one edge, or neither; which segments get flattened (FLATTEN_*,
 * `classify_bezier`'s `flatten`). */

REAL bezier_lerp(REAL a, REAL b, REAL t) {
    return t < (REAL)0.5 ? a + t * (b - a) : b - ((REAL)1 - t) * (b - a);
}

/* Bézier segment i: its degree (1..3) and control points 0..3 (`controls[8 i:]`, x y
 * interleaved; the slots a degree does not use repeat the end, so point 3 is the end). */
typedef struct {
    int degree;
    REAL x[4], y[4];
} Bezier;

Bezier bezier_at(__global const REAL *controls, __global const char *degree, long i) {
    Bezier b;
    b.degree = degree[i];
    for (int k = 0; k < 4; k++) {
        b.x[k] = controls[8 * i + 2 * k];
        b.y[k] = controls[8 * i + 2 * k + 1];
    }
    return b;
}

/* point_value: the 1-D Bézier (a[0]..a[degree]) at t, by de Casteljau. */
REAL point_value(int degree, const REAL *a, REAL t) {
    if (degree == 1)
        return bezier_lerp(a[0], a[1], t);
    if (degree == 2)
        return bezier_lerp(bezier_lerp(a[0], a[1], t), bezier_lerp(a[1], a[2], t), t);
    REAL b0 = bezier_lerp(a[0], a[1], t);
    REAL b1 = bezier_lerp(a[1], a[2], t);
    REAL b2 = bezier_lerp(a[2], a[3], t);
    return bezier_lerp(bezier_lerp(b0, b1, t), bezier_lerp(b1, b2, t), t);
}

/* The length of the second difference of control points k, k + 1, k + 2. */
REAL second_difference(const Bezier *b, int k) {
    return hypot(b->x[k] - (REAL)2 * b->x[k + 1] + b->x[k + 2],
                 b->y[k] - (REAL)2 * b->y[k + 1] + b->y[k + 2]);
}

long flatten_count(const Bezier *b, REAL tol) {
    if (b->degree == 1)
        return 1;
    REAL m;
    if (b->degree == 2)
        m = second_difference(b, 0) * (REAL)0.25;
    else
        m = (REAL)0.75 * py_max(second_difference(b, 0), second_difference(b, 1));
    if (!(m > tol))
        return 1;
    REAL n = ceil(sqrt(m / tol));
    return (long)py_min(n, (REAL)1.0e6);
}

/* Segment i (control points controls[8 i:], x y interleaved, degree[i]): its class, and
 * how many points flatten it within `tol` (`flatten_count`), or 0 where `flatten` does
 * not ask for its points. Inside is tested against the window a_* and beyond an edge
 * against the window r_*: the same window in float64; in float32 the window shrunk and
 * grown by the host so that both answers are sure for the float64 input (`_windows32`),
 * everything else ambiguous. */
__kernel void classify_bezier(__global const REAL *controls, __global const char *degree,
                              const long m, const REAL a_xmin, const REAL a_ymin,
                              const REAL a_xmax, const REAL a_ymax, const REAL r_xmin,
                              const REAL r_ymin, const REAL r_xmax, const REAL r_ymax,
                              const REAL tol, const int flatten,
                              __global uchar *segment_class, __global long *n_points) {
    long i = get_global_id(0);
    if (i >= m)
        return;
    Bezier b = bezier_at(controls, degree, i);
    Box accept = {a_xmin, a_ymin, a_xmax, a_ymax}, reject = {r_xmin, r_ymin, r_xmax, r_ymax};
    int c_or = 0, c_and = ~0;
    for (int k = 0; k <= b.degree; k++) {
        c_or |= box_outcode(b.x[k], b.y[k], accept);
        c_and &= box_outcode(b.x[k], b.y[k], reject);
    }
    uchar cls = c_or == 0 ? SEGMENT_ACCEPTED
                          : (c_and != 0 ? SEGMENT_REJECTED : SEGMENT_AMBIGUOUS);
    segment_class[i] = cls;
    int wanted = flatten == FLATTEN_ALL
                 || (flatten == FLATTEN_ACCEPTED_CURVES && cls == SEGMENT_ACCEPTED
                     && b.degree > 1);
    n_points[i] = wanted ? flatten_count(&b, tol) : 0;
}

/* Segment i's n_points[i] points at equal parameter steps k / n (its end point exactly
 * last), from points[point_end[i] - n_points[i]] on (`bezier.flatten_into`). */
__kernel void flatten_bezier(__global const REAL *controls, __global const char *degree,
                             __global const long *n_points, __global const long *point_end,
                             const long m, __global REAL *points) {
    long i = get_global_id(0);
    if (i >= m)
        return;
    Bezier b = bezier_at(controls, degree, i);
    long n = n_points[i];
    long pos = point_end[i] - n;
    for (long k = 1; k <= n; k++, pos++) {
        if (k == n) {
            points[2 * pos] = b.x[3];
            points[2 * pos + 1] = b.y[3];
        } else {
            REAL t = (REAL)k / (REAL)n;
            points[2 * pos] = point_value(b.degree, b.x, t);
            points[2 * pos + 1] = point_value(b.degree, b.y, t);
        }
    }
}

/* Run decisions (CURVE_RUN_*) of bezier.py's run level. */

/* Run r, the segments run_first[r]..run_end[r]-1 of one subpath: the outcodes of the
 * corners of its control points' box (`bezier._run_box`) accept it whole (not when
 * flattening: its curves must be flattened), reject it whole, or leave it to its
 * segments; a_* and r_* as in `classify_bezier`. */
__kernel void classify_bezier_runs(__global const REAL *controls,
                                   __global const long *run_first,
                                   __global const long *run_end, const long n_runs,
                                   const REAL a_xmin, const REAL a_ymin, const REAL a_xmax,
                                   const REAL a_ymax, const REAL r_xmin, const REAL r_ymin,
                                   const REAL r_xmax, const REAL r_ymax, const int flatten,
                                   __global char *run_decision) {
    long r = get_global_id(0);
    if (r >= n_runs)
        return;
    long a = run_first[r], b = run_end[r];
    Box box = point_box(controls[8 * a], controls[8 * a + 1]);
    for (long i = a; i < b; i++)
        for (int k = 1; k < 4; k++)  /* slot 0 is the previous segment's end (slot 3) */
            box = box_union(box,
                            point_box(controls[8 * i + 2 * k], controls[8 * i + 2 * k + 1]));
    Box accept = {a_xmin, a_ymin, a_xmax, a_ymax}, reject = {r_xmin, r_ymin, r_xmax, r_ymax};
    int inside = (box_outcode(box.xmin, box.ymin, accept)
                  | box_outcode(box.xmax, box.ymax, accept)) == 0;
    int beyond = (box_outcode(box.xmin, box.ymin, reject)
                  & box_outcode(box.xmax, box.ymax, reject)) != 0;
    run_decision[r] = (inside && !flatten) ? CURVE_RUN_ACCEPTED
                      : (beyond ? CURVE_RUN_REJECTED : CURVE_RUN_SEGMENTED);
}

/* --- kernels/windows.py: the (segment, window) pairs of many windows ------------------ */
/* `assign_pairs` is `assign_counts` and `assign_write` (one body, a `write` flag): the
 * same box, the same closed-cell and box tests, the same guess-and-correct on equally
 * spaced edges (`_low_cell`, `_high_cell`), the same binary searches and the same sweep
 * (from one ulp below bx0 - widest, `widest` rounded up by the host), so in float64 the
 * pairs are `rnsca.many_windows.assign`'s, in the same order. Work-item t of `items`
 * owns the segments t n / items .. (t + 1) n / items - 1 and counts its pairs of window
 * w in table[w items + t] (window-major): the host's exclusive scan of the table gives
 * every (window, work-item) its first slot, and the write pass puts the pairs there,
 * sorted by window then segment (a stable counting sort, as on the host). */

/* What `_visit` reads of the host's `WindowFinder` (`many_windows.window_finder`). */
typedef struct {
    int grid, uniform;
    REAL x_scale, y_scale;
    __global const REAL *xs;
    long n_xs;
    __global const REAL *ys;
    long n_ys;
    __global const long *cell_window;  /* (rows, cols) row-major */
    __global const REAL *windows;
    long k;
    __global const long *order;
    __global const REAL *xmins;
    REAL widest;
} Finder;

/* The first index of the sorted `edges` whose value is >= `value` (`_first_not_below`). */
long first_not_below(__global const REAL *edges, long count, REAL value) {
    long lo = 0, hi = count;
    while (lo < hi) {
        long mid = (lo + hi) / 2;
        if (edges[mid] < value)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The first index of the sorted `edges` whose value is > `value` (`_first_above`). */
long first_above(__global const REAL *edges, long count, REAL value) {
    long lo = 0, hi = count;
    while (lo < hi) {
        long mid = (lo + hi) / 2;
        if (edges[mid] <= value)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* `_guess`: the cell of `value` on equally spaced edges by arithmetic, off by one at most. */
long guess_cell(__global const REAL *edges, long count, REAL value, REAL scale) {
    long cells = count - 1;
    REAL g = (value - edges[0]) * scale;
    if (!(g > (REAL)0))  /* below the first edge, or NaN */
        return 0;
    if (g >= (REAL)(cells - 1))
        return cells - 1;
    return (long)g;
}

/* `_low_cell`: the first cell whose right edge is >= `value` (0 if none is below). */
long low_cell(__global const REAL *edges, long count, REAL value, REAL scale) {
    long g = guess_cell(edges, count, value, scale);
    while (g > 0 && edges[g] >= value)
        g--;
    while (g < count - 2 && edges[g + 1] < value)
        g++;
    return g;
}

/* `_high_cell`: the last cell whose left edge is <= `value` (-1 if none). */
long high_cell(__global const REAL *edges, long count, REAL value, REAL scale) {
    long g = guess_cell(edges, count, value, scale);
    while (g < count - 2 && edges[g + 1] <= value)
        g++;
    while (g >= 0 && edges[g] > value)
        g--;
    return g;
}

/* `_take`: count the pair (segment i, window w) of work-item t, or write it at its slot. */
void take_pair(long w, long t, long items, long i, int write, __global long *table,
               __global long *pair_segment, __global int *pair_window) {
    __global long *slot = table + w * items + t;
    if (write) {
        pair_segment[*slot] = i;
        pair_window[*slot] = (int)w;
    }
    *slot += 1;
}

/* `_visit`: count or write the pairs of segment i (its box against the windows). */
void visit_windows(__global const REAL *segments, long i, const Finder *f, long t,
                   long items, int write, __global long *table, __global long *pair_segment,
                   __global int *pair_window) {
    REAL x0 = segments[4 * i], y0 = segments[4 * i + 1];
    REAL x1 = segments[4 * i + 2], y1 = segments[4 * i + 3];
    REAL bx0 = py_min(x0, x1), by0 = py_min(y0, y1);
    REAL bx1 = py_max(x0, x1), by1 = py_max(y0, y1);
    if (f->grid) {
        __global const REAL *xs = f->xs, *ys = f->ys;
        long cols = f->n_xs - 1, rows = f->n_ys - 1;
        long c0, c1, r0, r1;
        /* Columns c with xs[c] <= bx1 and xs[c + 1] >= bx0 (closed cells). */
        if (f->uniform) {
            c0 = low_cell(xs, f->n_xs, bx0, f->x_scale);
            c1 = high_cell(xs, f->n_xs, bx1, f->x_scale);
            r0 = low_cell(ys, f->n_ys, by0, f->y_scale);
            r1 = high_cell(ys, f->n_ys, by1, f->y_scale);
        } else {
            c0 = max(first_not_below(xs, f->n_xs, bx0) - 1, 0L);
            c1 = min(first_above(xs, f->n_xs, bx1) - 1, cols - 1);
            r0 = max(first_not_below(ys, f->n_ys, by0) - 1, 0L);
            r1 = min(first_above(ys, f->n_ys, by1) - 1, rows - 1);
        }
        for (long r = r0; r <= r1; r++)
            for (long c = c0; c <= c1; c++)
                if (xs[c] <= bx1 && xs[c + 1] >= bx0 && ys[r] <= by1 && ys[r + 1] >= by0)
                    take_pair(f->cell_window[r * cols + c], t, items, i, write, table,
                              pair_segment, pair_window);
        return;
    }
    /* Sweep: the windows sorted by xmin; candidates have xmin in [bx0 - widest, bx1]. */
    long hi = first_above(f->xmins, f->k, bx1);
    /* One ulp below the rounded difference: never above the exact bx0 - widest. */
    long lo = first_not_below(f->xmins, f->k, nextafter(bx0 - f->widest, -INF_REAL));
    for (long s = lo; s < hi; s++) {
        long w = f->order[s];
        __global const REAL *win = f->windows + 4 * w;
        if (win[0] <= bx1 && win[2] >= bx0 && win[1] <= by1 && win[3] >= by0)
            take_pair(w, t, items, i, write, table, pair_segment, pair_window);
    }
}

/* One pass of the assignment (`write` 0: count into `table`, which it zeroes first;
 * 1: write at the slots the scan left in `table`). A segment that is not finite (as
 * `clip_segments` tests it) gets no pair; counting, the smallest such segment of each
 * group goes to first_bad[group] (n if none), and the host raises before writing. */
__kernel __attribute__((reqd_work_group_size(LOCAL_SIZE, 1, 1)))
void assign_pairs(__global const REAL *segments, const long n, const long items,
                  const int grid, const int uniform, const REAL x_scale, const REAL y_scale,
                  __global const REAL *xs, const long n_xs, __global const REAL *ys,
                  const long n_ys, __global const long *cell_window,
                  __global const REAL *windows, const long k, __global const long *order,
                  __global const REAL *xmins, const REAL widest, const int write,
                  __global long *table, __global long *pair_segment,
                  __global int *pair_window, __global long *first_bad) {
    __local long bad[LOCAL_SIZE];
    long t = get_global_id(0);
    long my_bad = n;
    if (t < items) {
        Finder f = {grid, uniform, x_scale, y_scale, xs, n_xs, ys, n_ys, cell_window,
                    windows, k, order, xmins, widest};
        if (!write)
            for (long w = 0; w < k; w++)
                table[w * items + t] = 0;
        long end = (t + 1) * n / items;
        for (long i = t * n / items; i < end; i++) {
            REAL x0 = segments[4 * i], y0 = segments[4 * i + 1];
            REAL x1 = segments[4 * i + 2], y1 = segments[4 * i + 3];
            if (!(isfinite(x0) && isfinite(y0) && isfinite(x1) && isfinite(y1)
                  && isfinite(x1 - x0) && isfinite(y1 - y0))) {
                if (my_bad == n)  /* a work-item's segments rise: its first is its smallest */
                    my_bad = i;
                continue;
            }
            visit_windows(segments, i, &f, t, items, write, table, pair_segment,
                          pair_window);
        }
    }
    if (write)
        return;
    store_first_bad(bad, my_bad, first_bad);
}

/* The smallest of the `groups` entries of first_bad into summary[1] (one work-group);
 * the scan of the table puts the count of pairs in summary[0]: the one read before the
 * write pass. */
__kernel __attribute__((reqd_work_group_size(LOCAL_SIZE, 1, 1)))
void reduce_first_bad(__global const long *first_bad, const long groups,
                      __global long *summary) {
    __local long part[LOCAL_SIZE];
    int l = get_local_id(0);
    long acc = LONG_MAX;
    for (long r = l; r < groups; r += LOCAL_SIZE)
        acc = min(acc, first_bad[r]);
    part[l] = acc;
    for (int step = LOCAL_SIZE / 2; step > 0; step /= 2) {
        barrier(CLK_LOCAL_MEM_FENCE);
        if (l < step)
            part[l] = min(part[l], part[l + step]);
    }
    if (l == 0)
        summary[1] = part[0];
}

/* offsets[w] (w = 0..k): the first of the `m` pieces, sorted by window, whose window is
 * >= w (a binary search; offsets[k] = m): the pieces' window offsets, made where the
 * pieces are, so only k + 1 numbers come back. */
__kernel void window_starts(__global const int *window, const long m, const long k,
                            __global long *offsets) {
    long w = get_global_id(0);
    if (w > k)
        return;
    long lo = 0, hi = m;
    while (lo < hi) {
        long mid = (lo + hi) / 2;
        if (window[mid] < w)
            lo = mid + 1;
        else
            hi = mid;
    }
    offsets[w] = lo;
}

/* --- Vector tiles of segment pieces (rnsca/backends/opencl/tiles.py) ---------------- */
/* Each piece, of `m` sorted by window (tile w's are window_offsets[w]..[w + 1] - 1), is
 * one LINESTRING feature of its tile's layer, written as rnsca/kernels/mvt.py writes it
 * (`feature_sizes`, `write_features`: the Numba backend's bytes, byte for byte):
 * 0x12 len (Layer.features), [0x08 id] (Feature.id, with a source), 0x18 0x02
 * (Feature.type LINESTRING), 0x22 len (Feature.geometry, packed): MoveTo 1 (0x09) and
 * its first end, LineTo 1 (0x0A) and the step to its second, zigzag-encoded from a
 * cursor at (0, 0). A piece whose ends quantise to one position is left out (the
 * specification's 4.3.4: a line of fewer than two positions). Three passes, as the
 * segments' compaction: the features' sizes, a prefix sum, the writes; then each tile's
 * framing (`write_tile_frames`). */

/* Bytes of `value` as a protobuf varint (mvt.py's _varint_size). */
long varint_size(ulong value) {
    long size = 1;
    while (value >= 128) {
        value >>= 7;
        size++;
    }
    return size;
}

/* Write `value` as a varint at out[pos]; return the position after (mvt.py's _varint). */
long write_varint(ulong value, __global uchar *out, long pos) {
    while (value >= 128) {
        out[pos++] = (uchar)((value & 127) | 128);
        value >>= 7;
    }
    out[pos] = (uchar)value;
    return pos + 1;
}

/* (n << 1) ^ (n >> 63), without shifting a negative number left. */
ulong zigzag(long n) {
    ulong doubled = (ulong)n << 1;
    return n < 0 ? ~doubled : doubled;
}

/* The tile of piece i: the last w with window_offsets[w] <= i (offsets[k] = m > i). */
long piece_tile(__global const long *window_offsets, long k, long i) {
    long lo = 0, hi = k;
    while (lo < hi) {
        long mid = (lo + hi) / 2;
        if (window_offsets[mid] <= i)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo - 1;
}

/* Piece i's ends in tile units (x0, y0, x1, y1; y down) into q, with tile w's
 * (x0, y1, sx, sy) in `quantisation`: floor((x - x0) * sx + 0.5), floor((y1 - y) * sy
 * + 0.5), each operation rounded (FP_CONTRACT OFF, as NumPy computes it on the host).
 * 0 where one is MVT_COORDINATE_LIMIT or more from the origin, or not finite: tested
 * before the conversion, which could otherwise overflow. */
int quantise_piece(__global const REAL *pieces, long i, __global const REAL *quantisation,
                   long w, long *q) {
    __global const REAL *g = quantisation + 4 * w;
    for (int e = 0; e < 2; e++) {
        REAL vx = (pieces[4 * i + 2 * e] - g[0]) * g[2] + (REAL)0.5;
        REAL vy = (g[1] - pieces[4 * i + 2 * e + 1]) * g[3] + (REAL)0.5;
        if (!(fabs(vx) < (REAL)MVT_COORDINATE_LIMIT && fabs(vy) < (REAL)MVT_COORDINATE_LIMIT))
            return 0;
        q[2 * e] = (long)floor(vx);
        q[2 * e + 1] = (long)floor(vy);
    }
    return 1;
}

/* Bytes of the packed geometry: two command integers of one byte, four parameters. */
long piece_geometry_size(const long *q) {
    return 2 + varint_size(zigzag(q[0])) + varint_size(zigzag(q[1]))
        + varint_size(zigzag(q[2] - q[0])) + varint_size(zigzag(q[3] - q[1]));
}

/* Bytes of the Feature message (mvt.py's _body_size, without tags); id < 0: none. */
long feature_body_size(long geometry, long id) {
    long size = 2 + 1 + varint_size(geometry) + geometry;
    if (id >= 0)
        size += 1 + varint_size(id);
    return size;
}

/* Pass 1: sizes[i], the bytes of piece i's Layer.features entry (0: left out). A
 * grid-stride loop; each group's first piece that does not quantise (`quantise_piece`)
 * goes to first_bad[group] (m if none). */
__kernel __attribute__((reqd_work_group_size(LOCAL_SIZE, 1, 1)))
void segment_feature_sizes(__global const REAL *pieces, const long m,
                           __global const long *source, const int has_source,
                           __global const long *window_offsets, const long k,
                           __global const REAL *quantisation, __global long *sizes,
                           __global long *first_bad) {
    __local long bad[LOCAL_SIZE];
    long my_bad = m;
    long stride = get_global_size(0);
    for (long i = get_global_id(0); i < m; i += stride) {
        long q[4];
        long size = 0;
        if (!quantise_piece(pieces, i, quantisation, piece_tile(window_offsets, k, i), q)) {
            if (my_bad == m)  /* a work-item's pieces rise: its first is its smallest */
                my_bad = i;
        } else if (q[0] != q[2] || q[1] != q[3]) {
            long body = feature_body_size(piece_geometry_size(q), has_source ? source[i] : -1);
            size = 1 + varint_size(body) + body;
        }
        sizes[i] = size;
    }
    store_first_bad(bad, my_bad, first_bad);
}

/* feature_start[w] (w = 0..k): the feature bytes of tiles before w (`position` is the
 * inclusive prefix sum of the sizes); feature_start[k + 1]: the first piece that does
 * not quantise (summary[1], from reduce_first_bad). The one read before the framing. */
__kernel void tile_feature_starts(__global const long *position,
                                  __global const long *window_offsets, const long k,
                                  __global const long *summary,
                                  __global long *feature_start) {
    long w = get_global_id(0);
    if (w > k + 1)
        return;
    if (w == k + 1) {
        feature_start[w] = summary[1];
        return;
    }
    long first = window_offsets[w];
    feature_start[w] = first > 0 ? position[first - 1] : 0;
}

/* The bytes of tile w's Layer message (head, features, tail), given its features'. */
long tile_layer_size(__global const long *feature_start, long w, long frame) {
    return frame + feature_start[w + 1] - feature_start[w];
}

/* Pass 3: piece i's Layer.features entry, after its tile's header (0x1A, the layer's
 * length, the `head_size` bytes of the layer's head) and the features before it in its
 * tile; tile w starts at tile_start[w] (the host's layout of the tiles). `frame` is
 * the head's and the tail's bytes together. */
__kernel void write_segment_features(__global const REAL *pieces, const long m,
                                     __global const long *source, const int has_source,
                                     __global const long *window_offsets, const long k,
                                     __global const REAL *quantisation,
                                     __global const long *sizes,
                                     __global const long *position,
                                     __global const long *feature_start,
                                     __global const long *tile_start, const long head_size,
                                     const long frame, __global uchar *out) {
    long i = get_global_id(0);
    if (i >= m || sizes[i] == 0)
        return;
    long w = piece_tile(window_offsets, k, i);
    long q[4];
    quantise_piece(pieces, i, quantisation, w, q);
    long layer = tile_layer_size(feature_start, w, frame);
    long pos = tile_start[w] + 1 + varint_size(layer) + head_size
        + (position[i] - sizes[i] - feature_start[w]);
    long geometry = piece_geometry_size(q);
    long id = has_source ? source[i] : -1;
    out[pos] = 0x12;  /* Layer.features, length-delimited */
    pos = write_varint(feature_body_size(geometry, id), out, pos + 1);
    if (id >= 0) {
        out[pos] = 0x08;  /* Feature.id, varint */
        pos = write_varint(id, out, pos + 1);
    }
    out[pos] = 0x18;  /* Feature.type, varint: LINESTRING */
    out[pos + 1] = 2;
    out[pos + 2] = 0x22;  /* Feature.geometry, packed */
    pos = write_varint(geometry, out, pos + 3);
    out[pos] = 0x09;  /* MoveTo, 1 */
    pos = write_varint(zigzag(q[0]), out, pos + 1);
    pos = write_varint(zigzag(q[1]), out, pos);
    out[pos] = 0x0A;  /* LineTo, 1 */
    pos = write_varint(zigzag(q[2] - q[0]), out, pos + 1);
    write_varint(zigzag(q[3] - q[1]), out, pos);
}

/* Each tile w holding a feature: Tile.layers (0x1A) and the layer's length, its head
 * bytes before the features and its tail bytes after them (mvt.py's write_tiles). */
__kernel void write_tile_frames(__global const long *feature_start,
                                __global const long *tile_start, const long k,
                                __global const uchar *head, const long head_size,
                                __global const uchar *tail, const long tail_size,
                                __global uchar *out) {
    long w = get_global_id(0);
    if (w >= k || feature_start[w + 1] == feature_start[w])
        return;
    long pos = tile_start[w];
    out[pos] = 0x1A;
    pos = write_varint(tile_layer_size(feature_start, w, head_size + tail_size), out,
                       pos + 1);
    for (long b = 0; b < head_size; b++)
        out[pos + b] = head[b];
    pos += head_size + feature_start[w + 1] - feature_start[w];
    for (long b = 0; b < tail_size; b++)
        out[pos + b] = tail[b];
}
