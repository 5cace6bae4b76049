/*
 * test_polygon_mc.h -- geometry shared by mfkit's polygon and LTC tests (tests/ only): whether a
 * ray from the origin hits a planar polygon (the Monte Carlo reference), a polygon with its
 * winding reversed, and a rotation about an axis.
 */
#ifndef MF_TEST_POLYGON_MC_H
#define MF_TEST_POLYGON_MC_H

#include <math.h>

#include <mfkit/mf_polygon.h>

/* (x, y) of v in the coordinate plane that drops component ax (0, 1, 2) of v. */
static inline void mf_test_project(mf_vec3 v, int ax, double *x, double *y)
{
    *x = ax == 0 ? v.y : (ax == 1 ? v.z : v.x);
    *y = ax == 0 ? v.z : (ax == 1 ? v.x : v.y);
}

/* 1 if the ray t w, t > 0, hits the planar polygon p: the crossing-number test in the polygon's
 * plane, projected on the coordinate plane that drops the largest component of its normal. */
static inline int mf_test_ray_hits(const mf_polygon *p, mf_vec3 w)
{
    /* Newell's normal: robust for any planar polygon */
    mf_vec3 n = {0, 0, 0};
    for (int i = 0; i < p->n; ++i) {
        mf_vec3 a = p->v[i], b = p->v[(i + 1) % p->n];
        n.x += (a.y - b.y) * (a.z + b.z);
        n.y += (a.z - b.z) * (a.x + b.x);
        n.z += (a.x - b.x) * (a.y + b.y);
    }
    double nw = mf_vec3_dot(n, w), d = mf_vec3_dot(n, p->v[0]);
    if (nw == 0.0 || d / nw <= 0.0)
        return 0;
    mf_vec3 x = mf_vec3_scale(w, d / nw);
    int ax = (fabs(n.x) > fabs(n.y)) ? (fabs(n.x) > fabs(n.z) ? 0 : 2) : (fabs(n.y) > fabs(n.z) ? 1 : 2);
    double px, py;
    mf_test_project(x, ax, &px, &py);
    int inside = 0;
    for (int i = 0, j = p->n - 1; i < p->n; j = i++) {
        double xi, yi, xj, yj;
        mf_test_project(p->v[i], ax, &xi, &yi);
        mf_test_project(p->v[j], ax, &xj, &yj);
        if (((yi > py) != (yj > py)) && (px < (xj - xi) * (py - yi) / (yj - yi) + xi))
            inside = !inside;
    }
    return inside;
}

/* p with its vertices in reverse order (the other side faces the origin). */
static inline mf_polygon mf_test_reversed(const mf_polygon *p)
{
    mf_polygon r = *p;
    for (int i = 0; i < p->n; ++i)
        r.v[i] = p->v[p->n - 1 - i];
    return r;
}

/* Rotation about the unit axis a by angle t (Rodrigues' formula). */
static inline mf_mat3 mf_test_rotation(mf_vec3 a, double t)
{
    double c = cos(t), s = sin(t), k = 1.0 - c;
    mf_mat3 r = {{{c + a.x * a.x * k, a.x * a.y * k - a.z * s, a.x * a.z * k + a.y * s},
                  {a.y * a.x * k + a.z * s, c + a.y * a.y * k, a.y * a.z * k - a.x * s},
                  {a.z * a.x * k - a.y * s, a.z * a.y * k + a.x * s, c + a.z * a.z * k}}};
    return r;
}

#endif /* MF_TEST_POLYGON_MC_H */
