/*
 * mf_ltc_lights.h -- line and disk lights integrated with an LTC [Heitz & Hill 2017, "Real-Time
 * Line- and Disk-Light Shading with Linearly Transformed Cosines", SIGGRAPH course notes].
 *
 * Positions are relative to the shading point, in the frame of the LTC (mf_ltc.h); results are
 * integrals of the LTC density D (mf_ltc_eval) and so, like mf_ltc_integrate_polygon, the
 * fraction of the lobe the light covers.
 *
 * Line.  A cylinder of small radius R around the segment p1 p2 is seen from the shading point as a
 * ribbon of width 2R perpendicular to the plane through the shading point and the segment, so its
 * integral is 2R times
 *     L(p1, p2) = integral over the segment of D(p/|p|) |p x t| / |p|^3 dl      (t = unit tangent),
 * the integral per unit width, in 1/length (the limit of the ribbon's integral / width, exact).
 * The linear map M^-1 takes the ribbon to a ribbon about the segment M^-1 p1, M^-1 p2 whose width
 * perpendicular to its own plane is that width times 1/|M^T n| (n = the unit normal of the
 * plane; normals transform with M^T), so [Heitz & Hill 2017, line lights]
 *     L(p1, p2) = L_o(M^-1 p1, M^-1 p2) / |M^T n|,
 *     |M^T n| = |(M^-1 p1) x (M^-1 p2)| / (|det M^-1| |p1 x p2|),
 * L_o the same integral of D_o = max(0, z)/pi over the segment clipped to z >= 0 (clipped after the
 * transform, as polygons: docs/math.md, correction C-T4).  In closed form, with the clipped segment
 * at signed distances l1 < l2 along t from the foot po of the perpendicular, d = |po|,
 * A = d^2 + l1^2, B = d^2 + l2^2, D = l2 - l1 (integrating (po.z + l t.z) d / (d^2 + l^2)^2 / pi):
 *     L_o = 1/(2 pi) [ (po.z/d) (D (d^2 - l1 l2) / (A B) + atan2(d D, d^2 + l1 l2) / d)
 *                      + t.z d D (l1 + l2) / (A B) ],
 * the differences of l/(d(d^2 + l^2)), atan(l/d) and d/(d^2 + l^2) taken without cancellation.
 * A line has no facing: it shades from every side.
 *
 * Disk (any ellipse).  Centre c and two conjugate semi-diameters v1, v2 (perpendicular semi-axes
 * for an ellipse, equal lengths for a disk): the points c + cos(phi) v1 + sin(phi) v2.  M^-1 maps
 * it to another ellipse, seen from the shading point as an elliptic cone.  The vector form factor
 * F = (1/pi) integral of w dw over it lies on the cone's axis (its two planes of symmetry), and
 * with the cone's cross-section at unit distance of semi-axes a, b (its orthographic projection
 * onto the plane across the axis is an ellipse of semi-axes a/sqrt(1 + a^2), b/sqrt(1 + b^2)):
 *     |F| = a b / sqrt((1 + a^2)(1 + b^2))                    [Heitz & Hill 2017, disk lights].
 * In the orthonormal frame (e1, e2, n) of the ellipse's axes, centre (x0, y0, 1) after scaling
 * by the distance of its plane and semi-axes 1/sqrt(alpha), 1/sqrt(beta) at that scale, the cone is
 * w^T Q w <= 0 with eigenvalues lambda1, lambda2 > 0 > lambda3, the roots of
 *     lambda^3 + c2 lambda^2 + c1 lambda + c0,   c0 = alpha beta,
 *     c1 = alpha beta (1 + x0^2 + y0^2) - alpha - beta,   c2 = 1 - alpha (1 + x0^2) - beta (1 + y0^2);
 * a^2 = -lambda3/lambda1, b^2 = -lambda3/lambda2 give |F|^2 = lambda3^2 / p'(lambda3) (p the
 * cubic: p'(lambda3) = (lambda1 - lambda3)(lambda2 - lambda3)), so only the negative root is needed
 * (found by the trigonometric formula, which is well conditioned for it even when the other two
 * meet, and one Newton step), and the axis is the eigenvector
 * (alpha x0 / (alpha - lambda3), beta y0 / (beta - lambda3), 1).  The horizon clipping is that of
 * the sphere approximation, mf_ltc_sphere_integral(|F|, F.z/|F|): exact while the cap of the same
 * form factor lies above the horizon, otherwise the "clipless" approximation of renderers (as
 * mf_ltc_integrate_polygon_sphere) [Heitz & Hill 2017].
 * Facing: a disk is front-facing when (v1 x v2).c > 0, the convention of mf_polygon.h for the
 * inscribed polygon c + v1, c + v2, c - v1, c - v2.
 */
#ifndef MF_LTC_LIGHTS_H
#define MF_LTC_LIGHTS_H

#include "mfkit/mf_ltc.h"

#ifdef __cplusplus
extern "C" {
#endif

/* L_o of the header: integral of max(0, z)/pi |p x t| / |p|^3 dl over the segment p1 p2 clipped to
 * z >= 0, in 1/length.  0 for a segment wholly below the horizon or on a line through the shading
 * point; NaN for non-finite input. */
double mf_line_integrate_cosine(mf_vec3 p1, mf_vec3 p2);

/* L(p1, p2) of the header: the LTC's integral over a thin cylinder (or ribbon) around the segment
 * p1 p2 per unit of its width (multiply by 2R for a cylinder of radius R), in 1/length; exact in the
 * limit of a thin light.  NaN for non-finite input or a NULL ltc. */
double mf_ltc_integrate_line(const mf_ltc *ltc, mf_vec3 p1, mf_vec3 p2);

/* The vector form factor (1/pi) integral of w dw of the ellipse (c, v1, v2) seen from the origin,
 * unsigned (pointing into the ellipse's cone).  NaN vector for non-finite input or a degenerate
 * ellipse (v1 x v2 = 0, or its plane through the origin). */
mf_vec3 mf_ellipse_form_factor(mf_vec3 c, mf_vec3 v1, mf_vec3 v2);

/* The LTC's integral over the ellipse (c, v1, v2): mf_ltc_sphere_integral of the form factor of
 * M^-1 applied to it (see the header).  ONE_SIDED: 0 when the ellipse faces away.  NaN outside the
 * domain of mf_ellipse_form_factor. */
double mf_ltc_integrate_disk(const mf_ltc *ltc, mf_vec3 c, mf_vec3 v1, mf_vec3 v2, mf_polygon_sided sided);

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_LIGHTS_H */
