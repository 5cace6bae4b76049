/*
 * mf_polygon.h -- spherical polygons seen from a shading point: solid angle, vector form factor,
 * and the integral of the normalised clamped cosine max(0, z) / pi (Lambert's formula).
 *
 * A polygon is a list of 3 to MF_POLYGON_MAX_VERTICES vertices, each the position of a corner
 * relative to the shading point (finite, non-zero; they need not be unit vectors).  The region is
 * the one enclosed by the geodesic edges between consecutive vertices (last to first): for a
 * planar polygon, its central projection onto the unit sphere.  Convex or not; the results below
 * are exact for simple polygons that lie in an open hemisphere (every planar polygon whose plane
 * misses the shading point); for self-intersecting ones, regions count with their winding number.
 *
 * Orientation.  A polygon is FRONT-FACING (it faces the shading point) when its vertices, seen
 * from the shading point, run CLOCKWISE -- equivalently, when the right-hand normal
 * (v1 - v0) x (v2 - v0) of a planar polygon points AWAY from the shading point.  This is the
 * orientation for which Lambert's edge sum below is positive, and the one-sided convention of
 * the reference LTC code (Heitz et al. 2016: sum = twoSided ? abs(sum) : max(0, sum)).
 * Example: the octant triangle (1,0,0), (0,1,0), (0,0,1) is front-facing.
 *
 * Measures: solid angle in steradians; the cosine integral and the form factor are
 * dimensionless (integrals of densities per steradian).
 *
 *  solid angle     Omega = |sum of the fan triangles (v0, vi, vi+1)|, each by
 *                  tan(Omega_i / 2) = a.(b x c) / (1 + a.b + b.c + c.a)  (unit a, b, c)
 *                  [Van Oosterom & Strackee 1983, "The Solid Angle of a Plane Triangle",
 *                  IEEE Trans. Biomed. Eng. 30(2)], with atan2 (all sizes, any sign).
 *  form factor     F = 1/(2 pi) sum_i theta_i normalize(v_i x v_i+1),  theta_i = angle(v_i, v_i+1)
 *                  = (1/pi) integral over P of w dw for a front-facing polygon (minus that for a
 *                  back-facing one): the vector irradiance of unit radiance divided by pi
 *                  [Lambert 1760; Baum et al. 1989, "Improving Radiosity Solutions Through the
 *                  Use of Analytically Determined Form-Factors", SIGGRAPH; Arvo 1995,
 *                  "Applications of Irradiance Tensors" (vector irradiance); Nahmias Sec. 2.2.4].
 *  cosine integral E = integral over P of max(0, z) / pi dw = F.z of the polygon clipped to
 *                  z >= 0 (Sutherland & Hodgman 1974 against the plane z = 0), signed by the
 *                  orientation; one-sided max(0, E), two-sided |E|.  This is the integral of
 *                  the LTC base density D_o = max(0, z)/pi [Nahmias Eq. 2.24, 2.33], i.e.
 *                  the irradiance from unit radiance divided by pi (docs/math.md, correction C-T3).
 *
 * Numerics (docs/math.md): each edge's angle is atan2(|a x b|, a.b) (no acos of values > 1),
 * and the edge sum is evaluated as sum (v_i - v_0) x (v_i+1 - v_0) + sum (theta_i / sin theta_i
 * - 1) (v_i x v_i+1), an exact rearrangement in which the first sum has no cancellation for
 * small polygons and the second is O(theta^2) smaller.  So a polygon of solid angle 1e-12 has
 * relative accuracy ~ eps / (its angular size) (1e-10 in the worst orientation, a few eps at the
 * zenith), which is the conditioning of its input coordinates; edges through the normal, vertices
 * on the horizon, collinear or repeated vertices are ordinary cases (no division by ~0).
 */
#ifndef MF_POLYGON_H
#define MF_POLYGON_H

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MF_POLYGON_MAX_VERTICES 8

typedef struct mf_polygon {
    int n;                                 /* vertex count, 3 .. MF_POLYGON_MAX_VERTICES */
    mf_vec3 v[MF_POLYGON_MAX_VERTICES];    /* corners relative to the shading point (any length) */
} mf_polygon;

/* Which faces of the polygon emit: ONE_SIDED counts only front-facing polygons (see above),
 * TWO_SIDED both. */
typedef enum mf_polygon_sided { MF_POLYGON_ONE_SIDED = 0, MF_POLYGON_TWO_SIDED = 1 } mf_polygon_sided;

/* A polygon from n vertices (copied).  n outside [3, MF_POLYGON_MAX_VERTICES] gives a polygon
 * with n = 0, which every function below treats as outside the domain (NaN). */
mf_polygon mf_polygon_make(int n, const mf_vec3 *v);

/* 1 if the polygon is in the domain: n in [3, MF_POLYGON_MAX_VERTICES], every used vertex
 * finite and non-zero.  The functions below return NaN (or a NaN vector) otherwise. */
int mf_polygon_valid(const mf_polygon *p);

/* Solid angle subtended at the shading point, in steradians, in [0, 4 pi); the signed version is
 * positive for front-facing polygons [Van Oosterom & Strackee 1983, triangle fan]. */
double mf_polygon_solid_angle(const mf_polygon *p);
double mf_polygon_solid_angle_signed(const mf_polygon *p);

/* Vector form factor F = 1/(2 pi) sum_edges theta_i normalize(v_i x v_i+1) of the whole
 * (unclipped) polygon [Baum et al. 1989]: (1/pi) integral over P of w dw, signed by the
 * orientation.  F.z is the cosine integral of a polygon above the horizon; |F| <= 1. */
mf_vec3 mf_polygon_form_factor(const mf_polygon *p);

/* Integral over the polygon of the normalised clamped cosine max(0, z) / pi, per steradian
 * (Lambert's formula on the polygon clipped to z >= 0).  ONE_SIDED: 0 for back-facing polygons;
 * TWO_SIDED: the orientation is ignored.  In [0, 1]; 1 for a polygon covering the upper
 * hemisphere; 0 for polygons below the horizon. */
double mf_polygon_integrate_cosine(const mf_polygon *p, mf_polygon_sided sided);

/* The same without the sign rule: positive for front-facing, negative for back-facing polygons
 * (the clipped F.z).  NaN outside the domain. */
double mf_polygon_integrate_cosine_signed(const mf_polygon *p);

#ifdef __cplusplus
}
#endif
#endif /* MF_POLYGON_H */
