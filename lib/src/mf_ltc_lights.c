/*
 * mf_ltc_lights.c -- line and disk lights with LTCs (see mf_ltc_lights.h for the derivations).
 */
#include "mfkit/mf_ltc_lights.h"

double mf_line_integrate_cosine(mf_vec3 p1, mf_vec3 p2)
{
    if (!mf_vec3_isfinite(p1) || !mf_vec3_isfinite(p2))
        return NAN;
    /* clip to z >= 0 */
    if (p1.z < 0.0 && p2.z < 0.0)
        return 0.0;
    if (p1.z < 0.0)
        p1 = mf_vec3_add(p1, mf_vec3_scale(mf_vec3_sub(p2, p1), p1.z / (p1.z - p2.z)));
    else if (p2.z < 0.0)
        p2 = mf_vec3_add(p2, mf_vec3_scale(mf_vec3_sub(p1, p2), p2.z / (p2.z - p1.z)));
    mf_vec3 e = mf_vec3_sub(p2, p1);
    double len = mf_vec3_length(e);
    if (!(len > 0.0))
        return 0.0;
    mf_vec3 t = mf_vec3_scale(e, 1.0 / len);
    double d = mf_vec3_length(mf_vec3_cross(p1, t)); /* distance of the line from the shading point */
    if (!(d > 0.0))
        return 0.0; /* seen end-on: no solid angle */
    double l1 = mf_vec3_dot(p1, t), l2 = l1 + len;
    mf_vec3 po = mf_vec3_sub(p1, mf_vec3_scale(t, l1));
    double d2 = d * d, a = d2 + l1 * l1, b = d2 + l2 * l2;
    /* (1/2pi) [ (po.z/d) (D (d^2 - l1 l2)/(A B) + atan2(d D, d^2 + l1 l2)/d) + t.z d D (l1 + l2)/(A B) ] */
    double i_po = len * (d2 - l1 * l2) / (a * b) + atan2(d * len, d2 + l1 * l2) / d;
    double i_t = d * len * (l1 + l2) / (a * b);
    return 0.5 * MF_INV_PI * ((po.z / d) * i_po + t.z * i_t);
}

double mf_ltc_integrate_line(const mf_ltc *ltc, mf_vec3 p1, mf_vec3 p2)
{
    if (!ltc || !mf_vec3_isfinite(p1) || !mf_vec3_isfinite(p2))
        return NAN;
    mf_vec3 q1 = mf_mat3_apply(ltc->inv, p1), q2 = mf_mat3_apply(ltc->inv, p2);
    double cross_o = mf_vec3_length(mf_vec3_cross(q1, q2));
    if (!(cross_o > 0.0))
        return 0.0; /* the line passes through the shading point */
    /* width factor 1/|M^T n| = |det M^-1| |p1 x p2| / |M^-1 p1 x M^-1 p2| */
    double w = ltc->abs_det_inv * mf_vec3_length(mf_vec3_cross(p1, p2)) / cross_o;
    return w * mf_line_integrate_cosine(q1, q2);
}

/* The cone of the ellipse (c, v1, v2): its unit axis (towards the ellipse) and |F|.  0 on success,
 * -1 for a degenerate ellipse or non-finite input. */
static int ellipse_cone(mf_vec3 c, mf_vec3 v1, mf_vec3 v2, mf_vec3 *axis, double *f_len)
{
    if (!mf_vec3_isfinite(c) || !mf_vec3_isfinite(v1) || !mf_vec3_isfinite(v2))
        return -1;
    /* principal semi-axes: eigenvectors of the Gram matrix of (v1, v2) mapped by [v1 v2] */
    double d11 = mf_vec3_dot(v1, v1), d22 = mf_vec3_dot(v2, v2), d12 = mf_vec3_dot(v1, v2);
    mf_vec3 nv = mf_vec3_cross(v1, v2);
    double area2 = mf_vec3_dot(nv, nv); /* = d11 d22 - d12^2 without cancellation */
    if (!(area2 > 0.0) || !isfinite(area2))
        return -1;
    double e_max = 0.5 * (d11 + d22 + hypot(d11 - d22, 2.0 * d12));
    double e_min = area2 / e_max;
    /* eigenvector of e_max: (d12, e_max - d11) or (e_max - d22, d12), whichever is longer */
    double x1 = d12, y1 = e_max - d11, x2 = e_max - d22, y2 = d12;
    double ex = x1, ey = y1;
    if (x2 * x2 + y2 * y2 > x1 * x1 + y1 * y1) {
        ex = x2;
        ey = y2;
    }
    mf_vec3 e1 = mf_vec3_add(mf_vec3_scale(v1, ex), mf_vec3_scale(v2, ey));
    double l1 = mf_vec3_length(e1);
    if (!(l1 > 0.0)) { /* a circle: any axis */
        e1 = v1;
        l1 = sqrt(d11);
    }
    e1 = mf_vec3_scale(e1, 1.0 / l1);
    mf_vec3 n = mf_vec3_scale(nv, 1.0 / sqrt(area2));
    double z0 = mf_vec3_dot(n, c);
    if (z0 < 0.0) {
        n = mf_vec3_scale(n, -1.0);
        z0 = -z0;
    }
    if (!(z0 > 0.0))
        return -1; /* the ellipse's plane contains the shading point */
    mf_vec3 e2 = mf_vec3_cross(n, e1);
    double x0 = mf_vec3_dot(e1, c) / z0, y0 = mf_vec3_dot(e2, c) / z0;
    double alpha = z0 * z0 / e_max, beta = z0 * z0 / e_min;
    /* the cubic of the cone's eigenvalues (header) */
    double c0 = alpha * beta;
    double c1 = alpha * beta * (1.0 + x0 * x0 + y0 * y0) - alpha - beta;
    double c2 = 1.0 - alpha * (1.0 + x0 * x0) - beta * (1.0 + y0 * y0);
    /* depressed: lambda = s - c2/3, s^3 + p s + q = 0, three real roots; the smallest is
     * -2 r cos((phi - pi)/3), r = sqrt(-p/3), phi = acos(-q / (2 r^3)) */
    double p = c1 - c2 * c2 / 3.0;
    double q = 2.0 * c2 * c2 * c2 / 27.0 - c2 * c1 / 3.0 + c0;
    double r = sqrt(fmax(-p / 3.0, 0.0));
    double cphi = r > 0.0 ? fmax(-1.0, fmin(1.0, -q / (2.0 * r * r * r))) : -1.0;
    double lam = -2.0 * r * cos((acos(cphi) - MF_PI) / 3.0) - c2 / 3.0;
    /* one Newton step on the cubic (polishes the rounding of p and q) */
    double pv = ((lam + c2) * lam + c1) * lam + c0, dv = (3.0 * lam + 2.0 * c2) * lam + c1;
    if (dv > 0.0)
        lam -= pv / dv;
    if (!(lam < 0.0))
        return -1;
    /* p'(lambda3) = (lambda1 - lambda3)(lambda2 - lambda3) = -c0/lambda3 + c2 lambda3 + 2 lambda3^2 */
    double dp = -c0 / lam + c2 * lam + 2.0 * lam * lam;
    if (!(dp > 0.0))
        return -1;
    *f_len = fmin(1.0, fabs(lam) / sqrt(dp));
    mf_vec3 ax = mf_vec3_add(mf_vec3_add(mf_vec3_scale(e1, alpha * x0 / (alpha - lam)),
                                         mf_vec3_scale(e2, beta * y0 / (beta - lam))),
                             n);
    *axis = mf_vec3_normalize(ax);
    return mf_vec3_isfinite(*axis) && isfinite(*f_len) ? 0 : -1;
}

mf_vec3 mf_ellipse_form_factor(mf_vec3 c, mf_vec3 v1, mf_vec3 v2)
{
    mf_vec3 axis;
    double f;
    if (ellipse_cone(c, v1, v2, &axis, &f) != 0)
        return mf_vec3_make(NAN, NAN, NAN);
    return mf_vec3_scale(axis, f);
}

double mf_ltc_integrate_disk(const mf_ltc *ltc, mf_vec3 c, mf_vec3 v1, mf_vec3 v2, mf_polygon_sided sided)
{
    if (!ltc || (sided != MF_POLYGON_ONE_SIDED && sided != MF_POLYGON_TWO_SIDED))
        return NAN;
    mf_vec3 axis;
    double f;
    if (ellipse_cone(mf_mat3_apply(ltc->inv, c), mf_mat3_apply(ltc->inv, v1), mf_mat3_apply(ltc->inv, v2), &axis,
                     &f) != 0)
        return NAN;
    if (sided == MF_POLYGON_ONE_SIDED && !(mf_vec3_dot(mf_vec3_cross(v1, v2), c) > 0.0))
        return 0.0;
    return mf_ltc_sphere_integral(f, axis.z);
}
