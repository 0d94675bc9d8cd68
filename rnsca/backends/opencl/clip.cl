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
 * (rnsca/kernels/outcode.py, segments.py, rnsca/baselines/*.py): the same formulas in
 * the same order, so in float64 the pieces agree with the Numba backend's to rounding
 * (in practice bit for bit). Read those modules for the geometry and the reasons; the
 * comments here only note what differs in C.
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

REAL clamp_real(REAL v, REAL low, REAL high) { return py_min(py_max(v, low), high); }

/* a = a0 + t * da as rounded, and its error (TwoProduct, TwoSum). */
REAL interpolate_dd(REAL a0, REAL da, REAL da_err, REAL t, REAL *err) {
    REAL p = t * da;
    REAL c = SPLITTER * t;
    REAL th = c - (c - t);
    REAL tl = t - th;
    c = SPLITTER * da;
    REAL dh = c - (c - da);
    REAL dl = da - dh;
    REAL p_err = (((th * dh - p) + th * dl) + tl * dh) + tl * dl;
    REAL a = a0 + p;
    REAL v = a - a0;
    REAL a_err = (a0 - (a - v)) + (p - v);
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

/* (d, d_err) with d + d_err == x1 - x0 exactly (Knuth's TwoSum). */
REAL difference_dd(REAL x1, REAL x0, REAL *d_err) {
    REAL d = x1 - x0;
    REAL v = d - x1;
    *d_err = (x1 - (d - v)) + (-x0 - v);
    return d;
}

/* b + ((e - a) / da) * db in double-double; returns the rounded value, *residual the rest. */
REAL line_coordinate_dd(REAL e, REAL a, REAL b, REAL da, REAL da_err, REAL db,
                               REAL db_err, REAL *residual) {
    REAL s = e - a;
    REAL v = s - e;
    REAL s_err = (e - (s - v)) + (-a - v);
    REAL t = s / da;
    REAL r = t * da;
    REAL c = SPLITTER * t;
    REAL th = c - (c - t);
    REAL tl = t - th;
    c = SPLITTER * da;
    REAL ah = c - (c - da);
    REAL al = da - ah;
    REAL r_err = (((th * ah - r) + th * al) + tl * ah) + tl * al;
    REAL t_lo = ((((s - r) - r_err) + s_err) - t * da_err) / da;
    REAL p = t * db;
    c = SPLITTER * db;
    REAL dh = c - (c - db);
    REAL dl = db - dh;
    REAL p_err = (((th * dh - p) + th * dl) + tl * dh) + tl * dl + (t_lo * db + t * db_err);
    REAL y = b + p;
    v = y - b;
    REAL y_err = (b - (y - v)) + (p - v);
    REAL ee = y_err + p_err;
    REAL z = y + ee;
    v = z - y;
    *residual = (y - (z - v)) + (ee - v);
    return z;
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

int is_piece(int degenerate, REAL t0, REAL t1, REAL ax, REAL ay, REAL bx, REAL by) {
    return (t0 <= t1) && (degenerate || ax != bx || ay != by);
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
    if (e0 == NO_EDGE && e1 == NO_EDGE)
        COUNT(st, ACCEPTED, 1);
    else
        COUNT(st, CLIPPED, 1);
    REAL ax, ay, bx, by;
    end_point(x0, y0, x1, y1, e0, x0, y0, xmin, ymin, xmax, ymax, &ax, &ay);
    end_point(x0, y0, x1, y1, e1, x1, y1, xmin, ymin, xmax, ymax, &bx, &by);
    out[0] = u0; out[1] = u1; out[2] = ax; out[3] = ay; out[4] = bx; out[5] = by;
    return is_piece(dx == 0 && dy == 0, u0, u1, ax, ay, bx, by);
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

/* Clip the leaf [ta, tb] on the flagged half-planes; out = (u0, u1, ax, ay, bx, by). */
int liang_barsky_leaf(REAL x0, REAL y0, REAL x1, REAL y1, REAL ta, REAL tb, REAL xa,
                             REAL ya, REAL xb, REAL yb, int flags, REAL xmin, REAL ymin,
                             REAL xmax, REAL ymax, REAL *out) {
    REAL u0 = ta, u1 = tb;
    int e0 = NO_EDGE, e1 = NO_EDGE;
    leaf_cut(LEFT, flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(RIGHT, flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(BOTTOM, flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(TOP, flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    out[0] = u0;
    out[1] = u1;
    end_point(x0, y0, x1, y1, e0, xa, ya, xmin, ymin, xmax, ymax, &out[2], &out[3]);
    end_point(x0, y0, x1, y1, e1, xb, yb, xmin, ymin, xmax, ymax, &out[4], &out[5]);
    return u0 <= u1;
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
            out[0] = t0; out[1] = t1; out[2] = ax; out[3] = ay; out[4] = bx; out[5] = by;
            return is_piece(dx == 0 && dy == 0, t0, t1, ax, ay, bx, by);
        }
        if (ca & cb) {
            COUNT(st, REJECTED, 1);
            return 0;
        }
        COUNT(st, CLIPPED, 1);
        COUNT(st, INTERSECTIONS, 1);
        int edge, bit;
        if (ca != 0) {
            REAL t = cs_edge_parameter(ca, x0, y0, dx, dy, xmin, ymin, xmax, ymax, &edge, &bit);
            if (t > t0) {
                t0 = t;
                ca = edge_point_code(x0, y0, x1, y1, edge, xmin, ymin, xmax, ymax, &ax, &ay);
            } else {
                ca &= ~bit;
            }
        } else {
            REAL t = cs_edge_parameter(cb, x0, y0, dx, dy, xmin, ymin, xmax, ymax, &edge, &bit);
            if (t < t1) {
                t1 = t;
                cb = edge_point_code(x0, y0, x1, y1, edge, xmin, ymin, xmax, ymax, &bx, &by);
            } else {
                cb &= ~bit;
            }
        }
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
            out[0] = 0; out[1] = 1; out[2] = x0; out[3] = y0; out[4] = x1; out[5] = y1;
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
    if (e0 == NO_EDGE && e1 == NO_EDGE)
        COUNT(st, ACCEPTED, 1);
    else
        COUNT(st, CLIPPED, 1);
    e0 = nln_original_edge(e0, flip_x, flip_y, swap);
    e1 = nln_original_edge(e1, flip_x, flip_y, swap);
    REAL ax, ay, bx, by;
    end_point(x0, y0, x1, y1, e0, x0, y0, xmin, ymin, xmax, ymax, &ax, &ay);
    end_point(x0, y0, x1, y1, e1, x1, y1, xmin, ymin, xmax, ymax, &bx, &by);
    out[0] = u0; out[1] = u1; out[2] = ax; out[3] = ay; out[4] = bx; out[5] = by;
    return is_piece(0, u0, u1, ax, ay, bx, by);
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
        out[0] = k.a; out[1] = k.a; out[2] = k.xa; out[3] = k.ya; out[4] = k.xa; out[5] = k.ya;
        return 1;
    }
    if (k.cb == 0) {
        out[0] = k.b; out[1] = k.b; out[2] = k.xb; out[3] = k.yb; out[4] = k.xb; out[5] = k.yb;
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
        out[0] = k.a; out[1] = k.b; out[2] = k.xa; out[3] = k.ya; out[4] = k.xb; out[5] = k.yb;
        return 1;
    }
    if (!exact) {
        COUNT(st, DROPPED, 1);
        return inside_end_only(k, out);
    }
    COUNT(st, CLIPPED, 1);
    int flags = (k.ca | k.cb) & UNSURE_BITS;
    int ok = liang_barsky_leaf(x0, y0, x1, y1, k.a, k.b, k.xa, k.ya, k.xb, k.yb, flags,
                               xmin, ymin, xmax, ymax, out);
    COUNT(st, INTERSECTIONS, count_divisions(flags));
    if (!ok) {
        return inside_end_only(k, out);
    }
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
    REAL leaf[6];
    if ((c0 | c1) == 0 || (c0 & c1) || max_depth == 0 || length <= tol) {
        Bracket whole = {0, x0, y0, wide(c0), 1, x1, y1, wide(c1), 0};
        int ok = midpoint_leaf(x0, y0, x1, y1, whole, exact, xmin, ymin, xmax, ymax, st, leaf);
        if (!ok || (!exact && leaf[0] == leaf[1] && (c0 | c1) != 0))
            return 0;
        for (int k = 0; k < 6; k++) out[k] = leaf[k];
        return is_piece(dx == 0 && dy == 0, leaf[0], leaf[1], leaf[2], leaf[3], leaf[4],
                        leaf[5]);
    }
    COUNT(st, EVALUATED, 1);
    COUNT(st, SUBDIVIDED, 1);
    REAL t0, t1, ax, ay, bx, by;
    if (c1 == 0) {
        t1 = 1; bx = x1; by = y1;
    } else {
        Bracket k = midpoint_search(x0, y0, dx, dy, x1, y1, wide(c0), wide(c1), length, 1,
                                    max_depth, tol, exact, xmin, ymin, xmax, ymax, st);
        if (!midpoint_leaf(x0, y0, x1, y1, k, exact, xmin, ymin, xmax, ymax, st, leaf))
            return 0;
        t1 = leaf[1]; bx = leaf[4]; by = leaf[5];
    }
    if (c0 == 0) {
        t0 = 0; ax = x0; ay = y0;
    } else {
        Bracket k = midpoint_search(x0, y0, dx, dy, x1, y1, wide(c0), wide(c1), length, 0,
                                    max_depth, tol, exact, xmin, ymin, xmax, ymax, st);
        if (!midpoint_leaf(x0, y0, x1, y1, k, exact, xmin, ymin, xmax, ymax, st, leaf))
            return 0;
        t0 = leaf[0]; ax = leaf[2]; ay = leaf[3];
    }
    out[0] = t0; out[1] = t1; out[2] = ax; out[3] = ay; out[4] = bx; out[5] = by;
    return is_piece(0, t0, t1, ax, ay, bx, by);
}

/* --- kernels/segments.py: RNSCA ----------------------------------------------------- */

int auto_n(REAL piece_length, REAL auto_piece) {
    if (!(piece_length > AUTO_N_MIN * auto_piece))
        return AUTO_N_MIN;
    REAL k = piece_length / auto_piece;
    return k > N_MAX ? N_MAX : (int)ceil(k);
}

/* The RNSCA stack, one per work-item: floats (ta, tb, xa, ya, xb, yb), ints (ca, cb, level). */
typedef struct {
    REAL f[STACK_CAPACITY][6];
    int i[STACK_CAPACITY][3];
} Stack;

/* Fold a clipped leaf (or accepted child) into the merged interval [lo, hi]. */
int rnsca_segment(REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin, REAL ymin, REAL xmax,
                         REAL ymax, int n_fixed, int max_depth, REAL tol, REAL auto_piece,
                         int exact, Counters st, Stack *stack, REAL *out) {
    REAL dx = x1 - x0;
    REAL dy = y1 - y0;
    int c0 = outcode(x0, y0, xmin, ymin, xmax, ymax);
    int c1 = outcode(x1, y1, xmin, ymin, xmax, ymax);
    COUNT(st, EVALUATED, 1);
    if ((c0 | c1) == 0) {
        COUNT(st, ACCEPTED, 1);
        COUNT(st, LEVELS, 1);
        out[0] = 0; out[1] = 1; out[2] = x0; out[3] = y0; out[4] = x1; out[5] = y1;
        return 1;
    }
    if (c0 & c1) {
        COUNT(st, REJECTED, 1);
        COUNT(st, LEVELS, 1);
        return 0;
    }
    REAL length = hypot(dx, dy);
    REAL lo_t = INF_REAL, lo_x = 0, lo_y = 0;
    REAL hi_t = -INF_REAL, hi_x = 0, hi_y = 0;
    REAL leaf[6];
    if (max_depth == 0 || length <= tol) {
        COUNT(st, LEVELS, 1);
        if (!exact) {
            COUNT(st, DROPPED, 1);
            return 0;
        }
        COUNT(st, CLIPPED, 1);
        int flags = c0 | c1;
        int ok = liang_barsky_leaf(x0, y0, x1, y1, 0, 1, x0, y0, x1, y1, flags,
                                   xmin, ymin, xmax, ymax, out);
        COUNT(st, INTERSECTIONS, count_divisions(flags));
        return ok && is_piece(0, out[0], out[1], out[2], out[3], out[4], out[5]);
    }
    COUNT(st, SUBDIVIDED, 1);
    stack->f[0][0] = 0; stack->f[0][1] = 1;
    stack->f[0][2] = x0; stack->f[0][3] = y0; stack->f[0][4] = x1; stack->f[0][5] = y1;
    REAL dx_err, dy_err;
    difference_dd(x1, x0, &dx_err);
    difference_dd(y1, y0, &dy_err);
    stack->i[0][0] = wide(c0);
    stack->i[0][1] = wide(c1);
    stack->i[0][2] = 0;
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
        int n = n_fixed > 0 ? n_fixed : auto_n(step * length, auto_piece);
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
                if (exact) {
                    COUNT(st, CLIPPED, 1);
                    int flags = (pc | c) & UNSURE_BITS;
                    int ok = liang_barsky_leaf(x0, y0, x1, y1, pt, t, px, py, x, y, flags,
                                               xmin, ymin, xmax, ymax, leaf);
                    COUNT(st, INTERSECTIONS, count_divisions(flags));
                    if (ok && is_piece(0, leaf[0], leaf[1], leaf[2], leaf[3], leaf[4], leaf[5])) {
                        if (leaf[0] < lo_t) {
                            lo_t = leaf[0]; lo_x = leaf[2]; lo_y = leaf[3];
                        }
                        if (leaf[1] > hi_t) {
                            hi_t = leaf[1]; hi_x = leaf[4]; hi_y = leaf[5];
                        }
                    }
                } else {
                    COUNT(st, DROPPED, 1);
                }
            } else {
                COUNT(st, SUBDIVIDED, 1);
                stack->f[sp][0] = pt; stack->f[sp][1] = t;
                stack->f[sp][2] = px; stack->f[sp][3] = py;
                stack->f[sp][4] = x; stack->f[sp][5] = y;
                stack->i[sp][0] = pc; stack->i[sp][1] = c; stack->i[sp][2] = level;
                sp += 1;
            }
            pt = t; px = x; py = y; pc = c;
        }
    }
    if (!(lo_t <= hi_t))
        return 0;
    out[0] = lo_t; out[1] = hi_t; out[2] = lo_x; out[3] = lo_y; out[4] = hi_x; out[5] = hi_y;
    return is_piece(0, lo_t, hi_t, lo_x, lo_y, hi_x, hi_y);
}

/* RNSCA's level 0 as the Numba block driver runs it (`_rnsca_block`): a segment that is
 * accepted, rejected, or a leaf (short, or max_depth 0) is decided here; only the
 * others go through the depth-first `rnsca_segment`. Same pieces, same counters. */
int rnsca_level0(REAL x0, REAL y0, REAL x1, REAL y1, REAL xmin, REAL ymin, REAL xmax,
                        REAL ymax, int n_fixed, int max_depth, REAL tol, REAL auto_piece,
                        int exact, Counters st, Stack *stack, REAL *out) {
    int c0 = outcode(x0, y0, xmin, ymin, xmax, ymax);
    int c1 = outcode(x1, y1, xmin, ymin, xmax, ymax);
    int reject = (c0 & c1) != 0;
    int amb = !reject && (c0 | c1) != 0;
    int split = amb && max_depth > 0 && (fabs(x1 - x0) + fabs(y1 - y0) > tol);
    if (split)
        return rnsca_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed, max_depth, tol,
                             auto_piece, exact, st, stack, out);
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
    leaf_cut(LEFT, flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(RIGHT, flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(BOTTOM, flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    leaf_cut(TOP, flags, &u0, &e0, &u1, &e1, x0, y0, x1, y1, xmin, ymin, xmax, ymax);
    if (reject || (amb && !exact))
        return 0;
    REAL ax, ay, bx, by;
    end_point(x0, y0, x1, y1, e0, x0, y0, xmin, ymin, xmax, ymax, &ax, &ay);
    end_point(x0, y0, x1, y1, e1, x1, y1, xmin, ymin, xmax, ymax, &bx, &by);
    out[0] = u0; out[1] = u1; out[2] = ax; out[3] = ay; out[4] = bx; out[5] = by;
    return u0 <= u1 && is_piece(x0 == x1 && y0 == y1, u0, u1, ax, ay, bx, by);
}

/* --- kernels --------------------------------------------------------------------------- */

/* Pass 1: clip segment i, store (t0, t1, ax, ay, bx, by) at result[6 i] and keep[i] in
 * {0, 1}; each group writes its summed counters to counters[group]. */
__kernel __attribute__((reqd_work_group_size(LOCAL_SIZE, 1, 1)))
void clip_segments(__global const REAL *segments, const long n, const REAL xmin,
                   const REAL ymin, const REAL xmax, const REAL ymax, const int method,
                   const int n_fixed, const int max_depth, const REAL tol,
                   const REAL auto_piece, const int exact, __global REAL *result,
                   __global long *keep, __global long *counters) {
    __local int st[SEGMENT_COUNTERS];
    for (int k = get_local_id(0); k < SEGMENT_COUNTERS; k += LOCAL_SIZE)
        st[k] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    long i = get_global_id(0);
    if (i < n) {
        REAL x0 = segments[4 * i], y0 = segments[4 * i + 1];
        REAL x1 = segments[4 * i + 2], y1 = segments[4 * i + 3];
        REAL out[6];
        int kept;
        if (method == RNSCA) {
            Stack stack;
            kept = rnsca_level0(x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed, max_depth,
                                tol, auto_piece, exact, st, &stack, out);
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
    barrier(CLK_LOCAL_MEM_FENCE);
    __global long *row = counters + get_group_id(0) * SEGMENT_COUNTERS;
    for (int k = get_local_id(0); k < SEGMENT_COUNTERS; k += LOCAL_SIZE)
        row[k] = st[k];
}

/* Pass 3: copy segment i's kept result to slot position[i] - 1 (`position` is the
 * inclusive prefix sum of `keep`), its ends clamped into the window (`_write_piece`). */
__kernel void write_pieces(__global const REAL *result, __global const long *keep,
                           __global const long *position, const long n, const REAL xmin,
                           const REAL ymin, const REAL xmax, const REAL ymax,
                           __global REAL *pieces, __global long *source, __global REAL *t) {
    long i = get_global_id(0);
    if (i >= n || !keep[i])
        return;
    long k = position[i] - 1;
    __global const REAL *r = result + 6 * i;
    pieces[4 * k] = clamp_real(r[2], xmin, xmax);
    pieces[4 * k + 1] = clamp_real(r[3], ymin, ymax);
    pieces[4 * k + 2] = clamp_real(r[4], xmin, xmax);
    pieces[4 * k + 3] = clamp_real(r[5], ymin, ymax);
    source[k] = i;
    t[2 * k] = r[0];
    t[2 * k + 1] = r[1];
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

/* Chunk k (of part chunk_part[k]): the box of its vertices, [xmin, ymin, xmax, ymax]. */
__kernel void chunk_boxes(__global const REAL *xy, __global const long *part_offsets,
                          __global const long *chunk_start, __global const long *chunk_part,
                          const long n_chunks, __global REAL *boxes) {
    long k = get_global_id(0);
    if (k >= n_chunks)
        return;
    long p = chunk_part[k];
    long first = part_offsets[p];
    long last = part_offsets[p + 1] - 1;
    long a = first + (k - chunk_start[p]) * RUN_LEAF_SEGMENTS;
    long b = min(a + RUN_LEAF_SEGMENTS, last);
    REAL lo_x = xy[2 * a], hi_x = lo_x, lo_y = xy[2 * a + 1], hi_y = lo_y;
    for (long i = a + 1; i <= b; i++) {
        lo_x = py_min(lo_x, xy[2 * i]);
        hi_x = py_max(hi_x, xy[2 * i]);
        lo_y = py_min(lo_y, xy[2 * i + 1]);
        hi_y = py_max(hi_y, xy[2 * i + 1]);
    }
    boxes[4 * k] = lo_x;
    boxes[4 * k + 1] = lo_y;
    boxes[4 * k + 2] = hi_x;
    boxes[4 * k + 3] = hi_y;
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
    for (int k = get_local_id(0); k < COUNTERS_WIDTH; k += LOCAL_SIZE)
        st[k] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    long p = get_global_id(0);
    if (p < n_parts) {
        long first = part_offsets[p];
        long last = part_offsets[p + 1] - 1;
        long chunk0 = chunk_start[p];
        int chunks = (int)chunk_count(first, last);
        long w = part_window[p];
        REAL xmin = windows[4 * w], ymin = windows[4 * w + 1];
        REAL xmax = windows[4 * w + 2], ymax = windows[4 * w + 3];
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
                __global const REAL *box = boxes + 4 * (chunk0 + ca);
                REAL lo_x = box[0], lo_y = box[1], hi_x = box[2], hi_y = box[3];
                for (long k = chunk0 + ca + 1; k < chunk0 + cb; k++) {
                    lo_x = py_min(lo_x, boxes[4 * k]);
                    lo_y = py_min(lo_y, boxes[4 * k + 1]);
                    hi_x = py_max(hi_x, boxes[4 * k + 2]);
                    hi_y = py_max(hi_y, boxes[4 * k + 3]);
                }
                int strict = lo_x > xmin && hi_x < xmax && lo_y > ymin && hi_y < ymax;
                int lo = outcode(lo_x, lo_y, xmin, ymin, xmax, ymax);
                int hi = outcode(hi_x, hi_y, xmin, ymin, xmax, ymax);
                if ((lo | hi) == 0 && (strict || !drop_edge_runs)) {
                    COUNT(st, RUNS_ACCEPTED, 1);
                    COUNT(st, RUN_LEVELS + slot, 1);
                    COUNT(st, SEGMENT_LEVELS + slot, b - a);
                    mark_chunks(decision, segmented, chunk0, ca, cb, CHUNK_ACCEPTED, first, last);
                } else if (lo & hi) {
                    COUNT(st, RUNS_REJECTED, 1);
                    COUNT(st, RUN_LEVELS + slot, 1);
                    COUNT(st, SEGMENT_LEVELS + slot, b - a);
                    mark_chunks(decision, segmented, chunk0, ca, cb, CHUNK_REJECTED, first, last);
                } else if (cb - ca <= 1 || sp + n_runs > RUN_STACK_CAPACITY) {
                    COUNT(st, RUNS_SEGMENTED, 1);
                    COUNT(st, RUN_LEVELS + slot, 1);
                    COUNT(st, SEGMENT_LEVELS + slot, b - a);
                    mark_chunks(decision, segmented, chunk0, ca, cb, CHUNK_SEGMENTED, first,
                                last);
                } else {
                    COUNT(st, RUNS_SUBDIVIDED, 1);
                    int k = min(n_runs, cb - ca);
                    for (int j = k; j > 0; j--) {
                        stack[sp][0] = ca + (int)((long)(cb - ca) * (j - 1) / k);
                        stack[sp][1] = ca + (int)((long)(cb - ca) * j / k);
                        levels[sp] = (uchar)(level + 1);
                        sp += 1;
                    }
                }
            }
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    __global long *row = counters + get_group_id(0) * COUNTERS_WIDTH;
    for (int k = get_local_id(0); k < COUNTERS_WIDTH; k += LOCAL_SIZE)
        row[k] = st[k];
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
                         const REAL tol, const REAL auto_piece, const int exact,
                         __global uchar *keep, __global REAL *result,
                         __global long *counters) {
    __local int st[COUNTERS_WIDTH];
    for (int k = get_local_id(0); k < COUNTERS_WIDTH; k += LOCAL_SIZE)
        st[k] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    long k = get_global_id(0);
    if (k < n_chunks && decision[k] == CHUNK_SEGMENTED) {
        long p = chunk_part[k];
        long first = part_offsets[p];
        long last = part_offsets[p + 1] - 1;
        long a = first + (k - chunk_start[p]) * RUN_LEAF_SEGMENTS;
        long b = min(a + RUN_LEAF_SEGMENTS, last);
        long slot = position[k] - segmented[k];
        long w = part_window[p];
        REAL xmin = windows[4 * w], ymin = windows[4 * w + 1];
        REAL xmax = windows[4 * w + 2], ymax = windows[4 * w + 3];
        Stack stack;
        for (long i = a; i < b; i++, slot++) {
            REAL x0 = xy[2 * i], y0 = xy[2 * i + 1], x1 = xy[2 * i + 2], y1 = xy[2 * i + 3];
            REAL out[6];
            int kept;
            if (method == RNSCA) {
                int c0 = outcode(x0, y0, xmin, ymin, xmax, ymax);
                int c1 = outcode(x1, y1, xmin, ymin, xmax, ymax);
                if ((c0 | c1) == 0 || (c0 & c1) != 0) {
                    COUNT(st, EVALUATED, 1);
                    COUNT(st, LEVELS, 1);
                    if (c0 & c1) {
                        COUNT(st, REJECTED, 1);
                        kept = 0;
                    } else {
                        COUNT(st, ACCEPTED, 1);
                        out[0] = 0; out[1] = 1; out[2] = x0; out[3] = y0; out[4] = x1;
                        out[5] = y1;
                        kept = 1;
                    }
                } else {
                    kept = rnsca_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, n_fixed,
                                         max_depth, tol, auto_piece, exact, st, &stack, out);
                }
            } else if (method == COHEN_SUTHERLAND) {
                kept = cohen_sutherland_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st, out);
            } else if (method == LIANG_BARSKY) {
                kept = liang_barsky_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st, out);
            } else if (method == NICHOLL_LEE_NICHOLL) {
                kept = nicholl_lee_nicholl_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, st,
                                                   out);
            } else {
                kept = midpoint_segment(x0, y0, x1, y1, xmin, ymin, xmax, ymax, max_depth, tol,
                                        exact, st, out);
            }
            keep[slot] = (uchar)kept;
            for (int j = 0; j < 6; j++)
                result[6 * slot + j] = kept ? out[j] : 0;
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    __global long *row = counters + get_group_id(0) * COUNTERS_WIDTH;
    for (int j = get_local_id(0); j < COUNTERS_WIDTH; j += LOCAL_SIZE)
        row[j] = st[j];
}

/* --- bezier.py: classification and flattening of Bézier segments ------------------ */

/* Segment classes (SEGMENT_*): by the outcodes of the control points, all inside, all
 * beyond one edge, or neither; which segments get flattened (FLATTEN_*,
 * `classify_bezier`'s `flatten`). */

REAL bezier_lerp(REAL a, REAL b, REAL t) {
    return t < (REAL)0.5 ? a + t * (b - a) : b - ((REAL)1 - t) * (b - a);
}

/* point_value: the 1-D Bézier (a0..a_degree) at t, by de Casteljau. */
REAL point_value(int degree, REAL a0, REAL a1, REAL a2, REAL a3, REAL t) {
    if (degree == 1)
        return bezier_lerp(a0, a1, t);
    if (degree == 2)
        return bezier_lerp(bezier_lerp(a0, a1, t), bezier_lerp(a1, a2, t), t);
    REAL b0 = bezier_lerp(a0, a1, t);
    REAL b1 = bezier_lerp(a1, a2, t);
    REAL b2 = bezier_lerp(a2, a3, t);
    return bezier_lerp(bezier_lerp(b0, b1, t), bezier_lerp(b1, b2, t), t);
}

long flatten_count(int degree, REAL x0, REAL x1, REAL x2, REAL x3, REAL y0, REAL y1,
                   REAL y2, REAL y3, REAL tol) {
    if (degree == 1)
        return 1;
    REAL m;
    if (degree == 2)
        m = hypot(x0 - (REAL)2 * x1 + x2, y0 - (REAL)2 * y1 + y2) * (REAL)0.25;
    else
        m = (REAL)0.75 * py_max(hypot(x0 - (REAL)2 * x1 + x2, y0 - (REAL)2 * y1 + y2),
                                hypot(x1 - (REAL)2 * x2 + x3, y1 - (REAL)2 * y2 + y3));
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
    __global const REAL *c = controls + 8 * i;
    int d = degree[i];
    int c_or = outcode(c[0], c[1], a_xmin, a_ymin, a_xmax, a_ymax)
               | outcode(c[2], c[3], a_xmin, a_ymin, a_xmax, a_ymax);
    int c_and = outcode(c[0], c[1], r_xmin, r_ymin, r_xmax, r_ymax)
                & outcode(c[2], c[3], r_xmin, r_ymin, r_xmax, r_ymax);
    if (d >= 2) {
        c_or |= outcode(c[4], c[5], a_xmin, a_ymin, a_xmax, a_ymax);
        c_and &= outcode(c[4], c[5], r_xmin, r_ymin, r_xmax, r_ymax);
    }
    if (d == 3) {
        c_or |= outcode(c[6], c[7], a_xmin, a_ymin, a_xmax, a_ymax);
        c_and &= outcode(c[6], c[7], r_xmin, r_ymin, r_xmax, r_ymax);
    }
    uchar cls = c_or == 0 ? SEGMENT_ACCEPTED
                          : (c_and != 0 ? SEGMENT_REJECTED : SEGMENT_AMBIGUOUS);
    segment_class[i] = cls;
    int wanted = flatten == FLATTEN_ALL
                 || (flatten == FLATTEN_ACCEPTED_CURVES && cls == SEGMENT_ACCEPTED && d > 1);
    n_points[i] = wanted ? flatten_count(d, c[0], c[2], c[4], c[6], c[1], c[3], c[5], c[7], tol)
                         : 0;
}

/* Segment i's n_points[i] points at equal parameter steps k / n (its end point exactly
 * last), from points[point_end[i] - n_points[i]] on (`bezier.flatten_into`). */
__kernel void flatten_bezier(__global const REAL *controls, __global const char *degree,
                             __global const long *n_points, __global const long *point_end,
                             const long m, __global REAL *points) {
    long i = get_global_id(0);
    if (i >= m)
        return;
    __global const REAL *c = controls + 8 * i;
    int d = degree[i];
    long n = n_points[i];
    long pos = point_end[i] - n;
    for (long k = 1; k <= n; k++, pos++) {
        if (k == n) {
            points[2 * pos] = c[6];
            points[2 * pos + 1] = c[7];
        } else {
            REAL t = (REAL)k / (REAL)n;
            points[2 * pos] = point_value(d, c[0], c[2], c[4], c[6], t);
            points[2 * pos + 1] = point_value(d, c[1], c[3], c[5], c[7], t);
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
    REAL lo_x = controls[8 * a], hi_x = lo_x, lo_y = controls[8 * a + 1], hi_y = lo_y;
    for (long i = a; i < b; i++) {
        for (int k = 1; k < 4; k++) {  /* slot 0 is the previous segment's end (slot 3) */
            REAL x = controls[8 * i + 2 * k], y = controls[8 * i + 2 * k + 1];
            lo_x = py_min(lo_x, x);
            hi_x = py_max(hi_x, x);
            lo_y = py_min(lo_y, y);
            hi_y = py_max(hi_y, y);
        }
    }
    int inside = (outcode(lo_x, lo_y, a_xmin, a_ymin, a_xmax, a_ymax)
                  | outcode(hi_x, hi_y, a_xmin, a_ymin, a_xmax, a_ymax)) == 0;
    int beyond = (outcode(lo_x, lo_y, r_xmin, r_ymin, r_xmax, r_ymax)
                  & outcode(hi_x, hi_y, r_xmin, r_ymin, r_xmax, r_ymax)) != 0;
    run_decision[r] = (inside && !flatten) ? CURVE_RUN_ACCEPTED
                      : (beyond ? CURVE_RUN_REJECTED : CURVE_RUN_SEGMENTED);
}
