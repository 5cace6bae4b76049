/*
 * mf_model_leadr_diffuse.c -- LEADR's rough diffuse BRDF for centred isotropic Beckmann slopes
 * (mf_model.h, name "leadr-diffuse").
 *
 * LEADR's diffuse radiance [Dupuy 2013, Eq. 21] under a directional light of unit irradiance from
 * wi, for centred slopes (mesonormal n = g = z, so the prefactor (n.g)/(n.wo) is 1/wo.z) and the
 * masking-aware irradiance of Eq. 20, E(wn) = <wn, wi> / (1 + Lambda(wo) + Lambda(wi)), is
 *
 *   f(wo, wi) wi.z = I / (pi wo.z (1 + Lambda(wo) + Lambda(wi))),
 *   I = integral P22(s) <wn(s), wi> <wn(s), wo> / wn(s).z  d^2 s,
 *
 * wn(s) = (-s_x, -s_y, 1) / sqrt(1 + |s|^2), <a, b> = max(0, a.b), Beckmann slopes
 * P22(s) = exp(-|s|^2 / alpha^2) / (pi alpha^2) (variance alpha^2 / 2 per axis, alpha^2 = 2 sigma^2,
 * mf_ndf.h).  The paper relates this model to Oren-Nayar; "oren-nayar" is Oren and Nayar's own
 * qualitative model (mf_model_oren_nayar.c).  For alpha -> 0 this is Lambert (wi.z / pi).
 *
 * Evaluation of I.  With d_i = wi.z - s.wi_xy = sqrt(1 + |s|^2) wn.wi (and d_o likewise), the
 * integrand is P22(s) d_i d_o / sqrt(1 + |s|^2) on the intersection of the half-planes d_i > 0,
 * d_o > 0 of the slope plane.  In polar slopes s = rho (cos phi, sin phi), a = w_xy.(cos phi, sin phi):
 *
 *   I = integral_0^inf w(rho) J(rho) d rho,   w(rho) = exp(-rho^2 / alpha^2) rho / (pi alpha^2 sqrt(1 + rho^2)),
 *   J(rho) = integral over the phi with rho a_i < wi.z and rho a_o < wo.z of (wi.z - rho a_i)(wo.z - rho a_o) dphi.
 *
 * On the circle of radius rho each half-plane removes one arc, centred on the azimuth of w_xy with
 * half-width acos(w.z / (rho |w_xy|)) once rho > w.z / |w_xy|; the integrand is a quadratic in
 * cos phi, sin phi, so J(rho) is exact in closed form: the whole circle, 2 pi wi.z wo.z +
 * pi rho^2 wi_xy.wo_xy, minus the integral over the union of the removed arcs (one or two arcs).
 * J is smooth in rho except at the radii where an arc appears (rho = w.z / |w_xy|, a square-root
 * onset) and where the two arcs start to overlap (the lines' crossing point, a kink); the rho
 * integral is split there and cut at RC alpha (RC = 6.5: the Gaussian tail beyond it is
 * exp(-42.25) = 4.5e-19 of the mass), and each panel [a, b] takes 16-point Gauss-Legendre in t
 * with rho = a + (b - a) t^2, which removes the square root at its start.  So one evaluation is at
 * most 7 x 16 nodes (the fixed breakpoints 1.5 alpha and 3 alpha split the Gaussian too), each
 * one exp, one sqrt and up to two acos (the arcs' ends by angle addition, make_arc): 3.5 us per
 * call against 6.7 us when each arc's ends took four sin/cos (200000 random calls, alpha 0.01..1,
 * both directions 1.1..89 deg, the same loaded machine; values equal within 2e-13 relative, the
 * rounding of whole - removed).  Accuracy against an
 * independent nested adaptive Gauss-Kronrod in Cartesian slopes (tests/test_models.c, 240 points,
 * alpha 1e-3 .. 1, theta_i, theta_o up to 89 deg, three azimuths): relative error 2.7e-9 at
 * worst; the test holds it to 1e-8 and prints the worst.  The
 * former 16 x 16 product rule over the sampled slopes was off by -8.7 % at alpha 1, 80 deg.
 * mf_leadr_diffuse is not used: its grid is LEADR's truncated, renormalised one (docs/math.md,
 * correction C-L7), and it evaluates the irradiance callback for every slope sample.
 * Sampler: the cosine hemisphere by the polar map (mf_model_sample_cosine_polar; the lobe is close
 * to Lambert).
 */
#include "mfkit/mf_model.h"

#include <stddef.h>

#include "mfkit/mf_smith.h"

/* Gauss-Legendre on [-1, 1], the nonnegative half of the nodes (the rest by symmetry). */
static const double gl16_x[8] = {0.095012509837637441, 0.28160355077925892, 0.45801677765722737, 0.61787624440264377,
                                 0.755404408355003,    0.86563120238783176, 0.9445750230732326,  0.98940093499164994};
static const double gl16_w[8] = {0.18945061045506847, 0.18260341504492361, 0.16915651939500256,  0.14959598881657682,
                                 0.12462897125553395, 0.095158511682492897, 0.062253523938647776, 0.027152459411754058};
#define RC 6.5

/* The integral over phi in [p0, p1] of (wi.z - rho a_i)(wo.z - rho a_o) (closed form), from the
 * arc's length p1 - p0 and the cosines and sines of its ends. */
static double arc_integral(mf_vec3 wi, mf_vec3 wo, double rho, double len, double c0, double s0, double c1, double s1)
{
    double int_c = s1 - s0, int_s = c0 - c1;               /* integrals of cos, sin */
    double int_cc = 0.5 * len + 0.5 * (s1 * c1 - s0 * c0); /* cos^2 */
    double int_ss = 0.5 * len - 0.5 * (s1 * c1 - s0 * c0); /* sin^2 */
    double int_cs = 0.5 * (s1 * s1 - s0 * s0);             /* sin cos */
    double lin = wi.z * (wo.x * int_c + wo.y * int_s) + wo.z * (wi.x * int_c + wi.y * int_s);
    double quad = wi.x * wo.x * int_cc + wi.y * wo.y * int_ss + (wi.x * wo.y + wi.y * wo.x) * int_cs;
    return wi.z * wo.z * len - rho * lin + rho * rho * quad;
}

/* The arc a half-plane w.z - rho a > 0 removes from the circle of radius rho (rho |w_xy| > w.z):
 * centred on w_xy's azimuth (cosine cc, sine sc), half-width h = acos(w.z / (rho |w_xy|)).  Its ends'
 * cosines and sines come from the angle-addition formulas with cos h = w.z / (rho |w_xy|) and
 * sin h = sqrt(1 - cos^2 h): one acos per arc, no sin or cos (the former evaluation called four
 * per arc; the value is the same up to rounding). */
typedef struct {
    double lo, hi;       /* ends, relative to phi_i */
    double c[2], s[2];   /* cos, sin of the absolute angles of lo and hi */
} arc;

static arc make_arc(double centre, double cc, double sc, double cos_h)
{
    arc a;
    double h = acos(cos_h), sin_h = sqrt(fmax(0.0, 1.0 - cos_h * cos_h));
    a.lo = centre - h;
    a.hi = centre + h;
    a.c[0] = cc * cos_h + sc * sin_h;
    a.s[0] = sc * cos_h - cc * sin_h;
    a.c[1] = cc * cos_h - sc * sin_h;
    a.s[1] = sc * cos_h + cc * sin_h;
    return a;
}

/* J(rho): the integral over the kept part of the circle of radius rho (see the header); (ci, si)
 * and (co, so) the cosine and sine of the azimuths of wi_xy and wo_xy, d = phi_o - phi_i reduced
 * to [-pi, pi]. */
static double ring(mf_vec3 wi, mf_vec3 wo, double rho, double len_i, double ci, double si, double len_o, double co,
                   double so, double d)
{
    double whole = 2.0 * MF_PI * wi.z * wo.z + MF_PI * rho * rho * (wi.x * wo.x + wi.y * wo.y);
    /* removed arcs, as [lo, hi] in angles relative to phi_i (the o arc within (-3 pi / 2, 3 pi / 2)) */
    arc a[2];
    int n = 0;
    if (rho * len_i > wi.z)
        a[n++] = make_arc(0.0, ci, si, wi.z / (rho * len_i));
    if (rho * len_o > wo.z)
        a[n++] = make_arc(d, co, so, wo.z / (rho * len_o));
    if (n == 2 && a[1].lo <= a[0].hi && a[0].lo <= a[1].hi) { /* overlapping: one arc */
        if (a[1].lo < a[0].lo) {
            a[0].lo = a[1].lo;
            a[0].c[0] = a[1].c[0];
            a[0].s[0] = a[1].s[0];
        }
        if (a[1].hi > a[0].hi) {
            a[0].hi = a[1].hi;
            a[0].c[1] = a[1].c[1];
            a[0].s[1] = a[1].s[1];
        }
        n = 1;
    }
    double removed = 0.0;
    for (int k = 0; k < n; ++k)
        removed += arc_integral(wi, wo, rho, a[k].hi - a[k].lo, a[k].c[0], a[k].s[0], a[k].c[1], a[k].s[1]);
    return whole - removed;
}

static double leadr_diffuse_eval_cos(const mf_brdf_model *m, const mf_brdf_params *prm, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha, value;
    if (!mf_model_iso_domain(prm, wo, wi, &alpha, &value))
        return value;
    const double rcut = RC * alpha, inv_a2 = 1.0 / (alpha * alpha);
    double lam_o = mf_smith_lambda_beckmann(alpha, alpha, wo), lam_i = mf_smith_lambda_beckmann(alpha, alpha, wi);
    double scale = MF_PI * alpha * alpha * MF_PI * wo.z * (1.0 + lam_o + lam_i);
    /* I is symmetric in (wi, wo): evaluate it for the pair in one canonical order, so that
     * f(wo, wi) / wi.z and f(wi, wo) / wo.z differ only in the last few roundings */
    if (wo.z < wi.z || (wo.z == wi.z && (wo.x < wi.x || (wo.x == wi.x && wo.y < wi.y)))) {
        mf_vec3 t = wi;
        wi = wo;
        wo = t;
    }
    double len_i = hypot(wi.x, wi.y), len_o = hypot(wo.x, wo.y);
    double phi_i = atan2(wi.y, wi.x), phi_o = atan2(wo.y, wo.x);
    if (!(len_i > 0.0)) /* no i arc: measure the o arc from its own azimuth */
        phi_i = phi_o;
    double d_io = remainder(phi_o - phi_i, 2.0 * MF_PI);
    double ci = len_i > 0.0 ? wi.x / len_i : 1.0, si = len_i > 0.0 ? wi.y / len_i : 0.0;
    double co = len_o > 0.0 ? wo.x / len_o : 1.0, so = len_o > 0.0 ? wo.y / len_o : 0.0;
    /* radial breakpoints: where each arc appears (onset[] = 1), where the lines cross, and 1.5,
     * 3 alpha and the cut 6.5 alpha (panels the width of the Gaussian's features) */
    double bp[8];
    int onset[8], nb = 0;
    const double fixed[4] = {0.0, 1.5 * alpha, 3.0 * alpha, rcut};
    for (int k = 0; k < 4; ++k)
        bp[nb] = fixed[k], onset[nb++] = 0;
    if (len_i > 0.0 && wi.z / len_i < rcut)
        bp[nb] = wi.z / len_i, onset[nb++] = 1;
    if (len_o > 0.0 && wo.z / len_o < rcut)
        bp[nb] = wo.z / len_o, onset[nb++] = 1;
    double det = wi.x * wo.y - wi.y * wo.x;
    if (det != 0.0) { /* P with wi_xy.P = wi.z, wo_xy.P = wo.z */
        double px = (wi.z * wo.y - wo.z * wi.y) / det, py = (wo.z * wi.x - wi.z * wo.x) / det;
        double r = hypot(px, py);
        if (r < rcut)
            bp[nb] = r, onset[nb++] = 0;
    }
    for (int i = 1; i < nb; ++i) /* insertion sort of (bp, onset) */
        for (int j = i; j > 0 && bp[j - 1] > bp[j]; --j) {
            double tb = bp[j];
            int to = onset[j];
            bp[j] = bp[j - 1], onset[j] = onset[j - 1];
            bp[j - 1] = tb, onset[j - 1] = to;
        }
    double sum = 0.0;
    for (int b = 0; b + 1 < nb; ++b) {
        double a0 = bp[b], len = bp[b + 1] - a0;
        if (!(len > 0.0))
            continue;
        double panel = 0.0;
        for (int k = 0; k < 8; ++k)
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                /* after an arc's onset rho = a + len t^2 (d rho = 2 len t dt: removes the square
                 * root), else rho = a + len t */
                double t = 0.5 * (1.0 + sgn * gl16_x[k]);
                double rho = onset[b] ? a0 + len * t * t : a0 + len * t, jac = onset[b] ? 2.0 * t : 1.0;
                double w = exp(-rho * rho * inv_a2) * rho / sqrt(1.0 + rho * rho);
                panel += gl16_w[k] * jac * w * ring(wi, wo, rho, len_i, ci, si, len_o, co, so, d_io);
            }
        sum += 0.5 * len * panel;
    }
    return sum / scale;
}

const mf_brdf_model mf_model_leadr_diffuse = {
    "leadr-diffuse", "LEADR rough diffuse, centred isotropic Beckmann slopes, accurate quadrature [Dupuy 2013, Eq. 20-21]",
    MF_MODEL_ENERGY_CONSERVING | MF_MODEL_RECIPROCAL, leadr_diffuse_eval_cos, mf_model_sample_cosine_polar, mf_model_pdf_cosine, NULL};
