/*
 * mf_polygon.c -- solid angle, vector form factor and clamped-cosine integral of spherical
 * polygons (see mf_polygon.h; derivations and the numerics in docs/math.md).
 */
#include "mfkit/mf_polygon.h"

#include <string.h>

#define TWO_PI (2.0 * MF_PI)
/* Sutherland-Hodgman against one plane keeps the z >= 0 vertices and adds one vertex per strict
 * crossing: at most n + n/2 vertices (each run of vertices below the plane, at least one vertex
 * long, adds two crossings). */
#define CLIP_MAX (MF_POLYGON_MAX_VERTICES + MF_POLYGON_MAX_VERTICES / 2)

mf_polygon mf_polygon_make(int n, const mf_vec3 *v)
{
    mf_polygon p;
    memset(&p, 0, sizeof p);
    if (n < 3 || n > MF_POLYGON_MAX_VERTICES || !v)
        return p;
    p.n = n;
    for (int i = 0; i < n; ++i)
        p.v[i] = v[i];
    return p;
}

int mf_polygon_valid(const mf_polygon *p)
{
    if (!p || p->n < 3 || p->n > MF_POLYGON_MAX_VERTICES)
        return 0;
    for (int i = 0; i < p->n; ++i) {
        mf_vec3 v = p->v[i];
        if (!mf_vec3_isfinite(v) || (v.x == 0.0 && v.y == 0.0 && v.z == 0.0))
            return 0;
    }
    return 1;
}

/* v / |v| for finite non-zero v, scaled by its largest component first so that neither
 * 1e-200 nor 1e200 coordinates under- or overflow in the squares. */
static mf_vec3 unit(mf_vec3 v)
{
    double m = fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z)));
    v = mf_vec3_scale(v, 1.0 / m);
    return mf_vec3_scale(v, 1.0 / mf_vec3_length(v));
}

/* Unit vertices of a valid polygon; 0 if it is not valid. */
static int unit_vertices(const mf_polygon *p, mf_vec3 *u)
{
    if (!mf_polygon_valid(p))
        return 0;
    for (int i = 0; i < p->n; ++i)
        u[i] = unit(p->v[i]);
    return p->n;
}

/* Signed solid angle of the fan (u0, ui, ui+1) of unit vectors: tan(Omega_i / 2) =
 * a.(b x c) / (1 + a.b + b.c + c.a) [Van Oosterom & Strackee 1983].  The triple product is
 * taken as a.((b - a) x (c - a)) (equal: a.(a x .) = 0), which has no cancellation when the
 * triangle is small: its factors are the short edge vectors. */
static double fan_solid_angle(const mf_vec3 *u, int n)
{
    double sum = 0.0;
    for (int i = 1; i + 1 < n; ++i) {
        mf_vec3 a = u[0], b = u[i], c = u[i + 1];
        double num = mf_vec3_dot(a, mf_vec3_cross(mf_vec3_sub(b, a), mf_vec3_sub(c, a)));
        double den = 1.0 + mf_vec3_dot(a, b) + mf_vec3_dot(b, c) + mf_vec3_dot(c, a);
        sum += 2.0 * atan2(num, den);
    }
    return sum;
}

/* 2 pi F = sum_i theta_i normalize(u_i x u_i+1) for unit vectors u (a closed polygon)
 * [Baum et al. 1989; Nahmias Sec. 2.2.4], rearranged for accuracy (docs/math.md):
 *   theta_i normalize(u_i x u_j) = (u_i x u_j) + (theta_i / s_i - 1) (u_i x u_j),  s_i = |u_i x u_j|,
 * and sum_i u_i x u_j = sum_i (u_i - u_0) x (u_j - u_0) exactly (the u_0 terms telescope), so
 * the O(theta) edge terms that cancel to the O(theta^2) area of a small polygon are never
 * formed; the correction (theta/sin theta - 1) (u_i x u_j) is O(theta^3).  theta_i =
 * atan2(s_i, u_i.u_j): no acos of a dot product that rounds above 1, no division by ~0 (the
 * ratio theta/s is ~1 for short edges; an edge with s = 0 has u_i x u_j = 0 and contributes
 * nothing, including exactly antipodal vertices, whose great circle is undefined). */
static mf_vec3 edge_sum(const mf_vec3 *u, int n)
{
    mf_vec3 area = {0.0, 0.0, 0.0}, corr = {0.0, 0.0, 0.0};
    for (int i = 0; i < n; ++i) {
        int j = (i + 1 == n) ? 0 : i + 1;
        area = mf_vec3_add(area, mf_vec3_cross(mf_vec3_sub(u[i], u[0]), mf_vec3_sub(u[j], u[0])));
        mf_vec3 x = mf_vec3_cross(u[i], u[j]);
        double s = mf_vec3_length(x);
        if (s > 0.0) {
            double theta = atan2(s, mf_vec3_dot(u[i], u[j]));
            corr = mf_vec3_add(corr, mf_vec3_scale(x, theta / s - 1.0));
        }
    }
    return mf_vec3_add(area, corr);
}

/* Sutherland & Hodgman 1974 against the plane z = 0, keeping z >= 0.  Vertices on the plane are
 * kept as they are; a new vertex is made only where an edge strictly crosses the plane, so no
 * duplicate vertices appear.  The crossing point lies on the chord between two unit vectors, so
 * its direction lies on their great circle: the clipped polygon has the same geodesic edges.
 * Returns the vertex count (0 .. CLIP_MAX); the output vertices are unit vectors. */
static int clip_horizon(const mf_vec3 *u, int n, mf_vec3 *out)
{
    int m = 0;
    for (int i = 0; i < n; ++i) {
        mf_vec3 a = u[i], b = u[(i + 1 == n) ? 0 : i + 1];
        if (a.z >= 0.0)
            out[m++] = a;
        if ((a.z > 0.0 && b.z < 0.0) || (a.z < 0.0 && b.z > 0.0)) {
            /* t in (0, 1): a.z and -b.z have the same sign, so a.z - b.z does not cancel */
            double t = a.z / (a.z - b.z);
            mf_vec3 q = mf_vec3_make(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), 0.0);
            /* q = 0 only for exactly antipodal a, b (the shading point on the edge): skipped */
            if (q.x != 0.0 || q.y != 0.0)
                out[m++] = unit(q);
        }
    }
    return m;
}

double mf_polygon_solid_angle_signed(const mf_polygon *p)
{
    mf_vec3 u[MF_POLYGON_MAX_VERTICES];
    int n = unit_vertices(p, u);
    return n ? fan_solid_angle(u, n) : NAN;
}

double mf_polygon_solid_angle(const mf_polygon *p) { return fabs(mf_polygon_solid_angle_signed(p)); }

mf_vec3 mf_polygon_form_factor(const mf_polygon *p)
{
    mf_vec3 u[MF_POLYGON_MAX_VERTICES];
    int n = unit_vertices(p, u);
    if (!n)
        return mf_vec3_make(NAN, NAN, NAN);
    return mf_vec3_scale(edge_sum(u, n), 1.0 / TWO_PI);
}

double mf_polygon_integrate_cosine_signed(const mf_polygon *p)
{
    mf_vec3 u[MF_POLYGON_MAX_VERTICES], c[CLIP_MAX];
    int n = unit_vertices(p, u);
    if (!n)
        return NAN;
    /* E = integral of max(0, z)/pi = F.z of the part above the horizon [Nahmias Eq. 2.24, 2.33] */
    int m = clip_horizon(u, n, c);
    if (m < 3)
        return 0.0; /* nothing above the horizon, or only a point or an arc on it */
    return edge_sum(c, m).z / TWO_PI;
}

double mf_polygon_integrate_cosine(const mf_polygon *p, mf_polygon_sided sided)
{
    double e = mf_polygon_integrate_cosine_signed(p);
    if (sided == MF_POLYGON_TWO_SIDED)
        return fabs(e);
    if (sided == MF_POLYGON_ONE_SIDED)
        return isnan(e) ? e : fmax(0.0, e);
    return NAN;
}
