/* test_energy.c -- the accurate albedo against the independent reference, its bound, the DFG
 * terms' Schlick identity, the Kulla-Conty furnace gate.  Deterministic (no random numbers). */
#include "mf_test.h"

#include "mfkit/mfkit.h"

#include <stdio.h>
#include <string.h>

#define DEG (MF_PI / 180.0)
/* the reference's tolerance; its achieved error is below its own estimate, printed on failure */
#define REF_TOL 1e-10

static void albedo_vs_reference(void)
{
    const double alphas[] = {1e-4, 1e-3, 0.05, 0.3, 0.5, 1.0};
    const double thetas[] = {0.0, 60.0, 85.0, 89.0, 89.78, 89.99};
    double worst_ratio = 0.0, worst_err = 0.0;
    for (int n = 0; n < 2; ++n)
        for (int a = 0; a < 6; ++a)
            for (int t = 0; t < 6; ++t) {
                mf_microfacet m = {mf_ndf_make(n ? MF_NDF_BECKMANN : MF_NDF_GGX, alphas[a], alphas[a]), MF_G2_JOINT,
                                   {MF_FRESNEL_NONE, 0, 0, 0}};
                mf_vec3 wo = mf_vec3_spherical(thetas[t] * DEG, 0.0);
                mf_result q, r;
                CHECK(mf_albedo_microfacet(&m, wo, &q) == MF_OK);
                mf_status s = mf_albedo_microfacet_reference(&m, wo, REF_TOL, &r);
                CHECK(s == MF_OK);
                double d = fabs(q.val - r.val);
                /* the bound must cover the difference (plus the reference's own bound) and be <= 1e-9,
                 * the target, over the whole domain: alpha 1e-4..1, theta up to 89.99 deg */
                if (!(d <= q.err + r.err) || !(q.err <= 1e-9) || s != MF_OK)
                    printf("ndf %d alpha %g theta %g: %.15f err %.2e vs reference %.15f (err %.1e, status %d), diff "
                           "%.2e\n",
                           n, alphas[a], thetas[t], q.val, q.err, r.val, r.err, (int)s, d);
                CHECK(d <= q.err + r.err);
                CHECK(q.err <= 1e-9);
                worst_err = fmax(worst_err, q.err);
                worst_ratio = fmax(worst_ratio, d / (q.err + r.err));
            }
    printf("albedo vs reference: 72 points, worst bound %.2e, worst |diff| / (bound + reference bound) %.3f\n",
           worst_err, worst_ratio);
    /* the reference against the second, older one (spherical angles of wi) where that one converges:
     * two quadratures in different coordinates agree within both bounds */
    const double ca[][2] = {{0.05, 0.0}, {0.5, 60.0}, {1.0, 85.0}, {0.3, 30.0}};
    for (int n = 0; n < 2; ++n)
        for (int i = 0; i < 4; ++i) {
            mf_microfacet m = {mf_ndf_make(n ? MF_NDF_BECKMANN : MF_NDF_GGX, ca[i][0], ca[i][0]), MF_G2_JOINT,
                               {MF_FRESNEL_NONE, 0, 0, 0}};
            mf_vec3 wo = mf_vec3_spherical(ca[i][1] * DEG, 0.0);
            mf_result r, rw;
            CHECK(mf_albedo_microfacet_reference(&m, wo, REF_TOL, &r) == MF_OK);
            CHECK(mf_albedo_microfacet_reference_wi(&m, wo, REF_TOL, &rw) == MF_OK);
            if (!(fabs(r.val - rw.val) <= r.err + rw.err))
                printf("references disagree: ndf %d alpha %g theta %g: %.15f vs %.15f\n", n, ca[i][0], ca[i][1], r.val,
                       rw.val);
            CHECK(fabs(r.val - rw.val) <= r.err + rw.err);
        }
    /* the value of the issue: GGX alpha 0.5, normal view, 0.68784852 to 1e-8 */
    mf_microfacet g = {mf_ndf_make(MF_NDF_GGX, 0.5, 0.5), MF_G2_JOINT, {MF_FRESNEL_NONE, 0, 0, 0}};
    mf_result q;
    CHECK(mf_albedo_microfacet(&g, mf_vec3_make(0, 0, 1), &q) == MF_OK);
    CHECK(fabs(q.val - 0.68784852) < 1e-8);
}

/* the Charlie channel against its reference (other coordinates: wi instead of the micro-normal),
 * over the table's domain including the grazing, smallest-alpha corner where it exceeds 30 */
static void charlie_vs_reference(void)
{
    const double alphas[] = {1e-4, 1e-2, 0.3, 1.0};
    const double mus[] = {1.0, 0.5, 0.05, 0.0039, 1.745e-4};
    double worst = 0.0;
    for (int a = 0; a < 4; ++a)
        for (int t = 0; t < 5; ++t) {
            mf_result q, r;
            CHECK(mf_albedo_charlie(alphas[a], mus[t], &q) == MF_OK);
            CHECK(mf_albedo_charlie_reference(alphas[a], mus[t], REF_TOL, &r) == MF_OK);
            double d = fabs(q.val - r.val);
            if (!(d <= q.err + r.err) || !(q.err <= 1e-9))
                printf("charlie alpha %g mu %g: %.15g err %.2e vs reference %.15g err %.2e\n", alphas[a], mus[t], q.val,
                       q.err, r.val, r.err);
            CHECK(d <= q.err + r.err);
            CHECK(q.err <= 1e-9);
            worst = fmax(worst, d / (q.err + r.err));
        }
    /* closed form at normal incidence, alpha 1: D = 3 sin(t) / (2 pi), V = 1/4, wi.z = cos 2t,
     * wo.h = cos t, so the albedo is 3 int_0^{pi/4} sin^2 t cos t cos 2t dt = 3 (u^3/3 - 2 u^5/5) at
     * u = 1/sqrt(2), = 1 / (5 sqrt(2)); within the bound */
    mf_result q;
    CHECK(mf_albedo_charlie(1.0, 1.0, &q) == MF_OK);
    CHECK(fabs(q.val - 1.0 / (5.0 * sqrt(2.0))) <= q.err);
    printf("charlie vs reference: 20 points, worst |diff| / bounds %.3f; alpha 1 normal %.15f\n", worst, q.val);
}

/* 2 int_0^1 E_T(mu) mu dmu = 4 int_0^1 E_T(s^2) s^3 ds on [0, s_c], [s_c, 1] with an n-point rule
 * (s_c^2 = the cosine of the critical angle on the dense side, where E_T turns over; 0.5 if none);
 * *b gets the propagated bounds */
static double transmit_avg(double alpha, double eta, int n, double *b)
{
    double x[32], w[32], sum = 0.0, sc = eta < 1.0 ? sqrt(sqrt(1.0 - eta * eta)) : 0.5;
    CHECK(mf_quad_gauss_legendre(n, x, w) == MF_OK);
    *b = 0.0;
    for (int p = 0; p < 2; ++p) {
        double a = p ? sc : 0.0, h = 0.5 * (p ? 1.0 - sc : sc);
        for (int j = 0; j < n; ++j) {
            double t = a + h * (1.0 + x[j]), wt = h * w[j] * 4.0 * t * t * t;
            mf_result r, tr;
            CHECK(mf_albedo_dielectric(mf_ndf_make(MF_NDF_GGX, alpha, alpha), MF_G2_JOINT, t * t, eta, &r, &tr) == MF_OK);
            sum += wt * tr.val;
            *b += wt * tr.err;
        }
    }
    return sum;
}

/* the rough dielectric: three checks that share no code with its rule */
static void dielectric(void)
{
    const double alphas[] = {1e-4, 0.01, 0.3, 1.0};
    const double mus[] = {1.0, 0.5, 0.05, 1.745e-4};
    for (int n = 0; n < 2; ++n)
        for (int a = 0; a < 4; ++a)
            for (int t = 0; t < 4; ++t)
                for (int g = 0; g < 2; ++g) {
                    /* eta = 1: no refraction (wt = -wo), F = 0, so E_R = 0 and E_T = (1 + Lambda_o) G2(wo, wo)
                     * (int D (wo.h)_+ dh = wo.z (1 + Lambda_o)): 1 / (1 + 2 L) joint (times 1 + L), 1 / (1 + L)
                     * separable */
                    mf_ndf ndf = mf_ndf_make(n ? MF_NDF_BECKMANN : MF_NDF_GGX, alphas[a], alphas[a]);
                    mf_g2_form g2 = g ? MF_G2_SEPARABLE : MF_G2_JOINT;
                    double mu = mus[t];
                    mf_result r, tr;
                    CHECK(mf_albedo_dielectric(ndf, g2, mu, 1.0, &r, &tr) == MF_OK);
                    double l = mf_smith_lambda(ndf, mf_vec3_make(sqrt(1.0 - mu * mu), 0.0, mu));
                    double exact = g ? 1.0 / (1.0 + l) : (1.0 + l) / (1.0 + 2.0 * l);
                    if (!(fabs(tr.val - exact) <= tr.err) || !(fabs(r.val) <= 1e-15) || !(tr.err <= 1e-9))
                        printf("dielectric eta 1: ndf %d g2 %d alpha %g mu %g: E_T %.15f err %.1e vs %.15f, E_R %g\n", n, g,
                               alphas[a], mu, tr.val, tr.err, exact, r.val);
                    CHECK(fabs(tr.val - exact) <= tr.err);
                    CHECK(tr.err <= 1e-9);
                    CHECK(fabs(r.val) <= 1e-15); /* F(eta = 1) is 0 up to the rounding of its formula */
                    /* eta 1.5 and 3 (no total internal reflection): E_R against mf_albedo_microfacet with the
                     * dielectric Fresnel (the slope-space rule) within both bounds */
                    for (int e = 0; e < 2; ++e) {
                        double eta = e ? 3.0 : 1.5;
                        mf_microfacet m = {ndf, g2, {MF_FRESNEL_DIELECTRIC, 0.0, eta, 0.0}};
                        mf_result q;
                        CHECK(mf_albedo_dielectric(ndf, g2, mu, eta, &r, &tr) == MF_OK);
                        CHECK(mf_albedo_microfacet(&m, mf_vec3_make(sqrt(1.0 - mu * mu), 0.0, mu), &q) == MF_OK);
                        if (!(fabs(r.val - q.val) <= r.err + q.err) || !(r.err <= 1e-9) || !(tr.err <= 1e-9))
                            printf("dielectric eta %g: ndf %d g2 %d alpha %g mu %g: E_R %.15f (%.1e) vs albedo %.15f (%.1e), "
                                   "E_T err %.1e\n",
                                   eta, n, g, alphas[a], mu, r.val, r.err, q.val, q.err, tr.err);
                        CHECK(fabs(r.val - q.val) <= r.err + q.err);
                        CHECK(r.err <= 1e-9 && tr.err <= 1e-9);
                    }
                }
    /* reciprocity: a uniform radiance L outside sends pi L T_avg(eta) into the dense side; in
     * equilibrium the radiance inside is eta^2 L and sends pi eta^2 L T_avg(1/eta) back, so
     * T_avg(eta) = eta^2 T_avg(1/eta) (the single-scattering BTDF is reciprocal and this G2 is symmetric).
     * The two sides' integrals have different kinks (total internal reflection only inside).  Tolerance:
     * each average's |Q24 - Q16| plus the propagated bounds. */
    for (int a = 0; a < 2; ++a) {
        double alpha = a ? 1.0 : 0.3, eta = 1.5, b1, b2, b3, b4;
        double out = transmit_avg(alpha, eta, 24, &b1), out16 = transmit_avg(alpha, eta, 16, &b2);
        double in = transmit_avg(alpha, 1.0 / eta, 24, &b3), in16 = transmit_avg(alpha, 1.0 / eta, 16, &b4);
        double tol = fabs(out - out16) + b1 + b2 + eta * eta * (fabs(in - in16) + b3 + b4);
        printf("dielectric reciprocity alpha %g: T_avg(1.5) %.12f, 1.5^2 T_avg(1/1.5) %.12f, diff %.2e, tolerance %.2e\n",
               alpha, out, eta * eta * in, out - eta * eta * in, tol);
        CHECK(fabs(out - eta * eta * in) <= tol);
    }
}

/* ---- the dielectric reference near total internal reflection, against a very-high-order rule ---- */

/* A fixed product Gauss-Legendre rule, written here from the formulas alone, for E_R and E_T in the
 * micro-normal's angles (beta, psi) about wo = (s, 0, c) (wo.h = cos beta: total internal reflection
 * is beta > beta_c = asin(eta)).  Its panels end on every kink, in closed form: in psi at pi/2 and
 * where the kink curves meet (beta_k(psi) = beta_c: cos psi = c / (s tan 2 beta_c); beta_h(psi) =
 * beta_c: cos psi = c / (s tan beta_c); the transmission's horizon reaching beta_c: cos psi =
 * -c tan(beta_c) / s), graded towards the peak of D at psi = pi; in beta at beta_c, at
 * beta_k = atan2(c, s cos psi) / 2 (E_R's end), at min(beta_h, pi/2) and at the one root of wt.z
 * (E_T's end, bisected).  Every panel is cut in 4 with n points each, and the quarters beside a
 * square-root kink (beta_c, the psi events) are integrated in u with x = kink +- u^2.  Two orders,
 * n and 2n: their difference estimates the error of the higher one. */
typedef struct {
    double s, c, eta, alpha;
    int trans, n;
    const double *xs, *ws;
} gl_ctx;

static double gl_point(const gl_ctx *g, double beta, double psi)
{
    double cb = cos(beta), sb = sin(beta), cp = cos(psi), sp = sin(psi);
    mf_vec3 wo = mf_vec3_make(g->s, 0.0, g->c);
    mf_vec3 h = mf_vec3_make(cb * g->s + sb * cp * g->c, sb * sp, cb * g->c - sb * cp * g->s);
    if (!(h.z > 0.0) || !(cb > 0.0))
        return 0.0;
    mf_ndf ndf = mf_ndf_make(MF_NDF_GGX, g->alpha, g->alpha);
    double F = mf_fresnel_dielectric(g->eta, cb), base = mf_ndf_d(ndf, h) * cb / g->c * sb;
    if (!g->trans) {
        mf_vec3 wi = mf_vec3_make(2 * cb * h.x - wo.x, 2 * cb * h.y, 2 * cb * h.z - wo.z);
        return wi.z > 0.0 ? base * F * mf_smith_g2(ndf, MF_G2_JOINT, wo, wi) : 0.0;
    }
    double ct2 = 1.0 - sb * sb / (g->eta * g->eta);
    if (!(ct2 > 0.0) || !(F < 1.0))
        return 0.0;
    double k = cb / g->eta - sqrt(ct2);
    mf_vec3 wt = mf_vec3_make(-wo.x / g->eta + k * h.x, k * h.y, -wo.z / g->eta + k * h.z);
    return wt.z < 0.0 ? base * (1.0 - F) * mf_smith_g2(ndf, MF_G2_JOINT, wo, mf_vec3_make(wt.x, wt.y, -wt.z)) : 0.0;
}

static double gl_wtz(const gl_ctx *g, double beta, double psi)
{
    double cb = cos(beta), sb = sin(beta), ct2 = 1.0 - sb * sb / (g->eta * g->eta);
    double hz = cb * g->c - sb * cos(psi) * g->s;
    return ct2 > 0.0 ? -g->c / g->eta + (cb / g->eta - sqrt(ct2)) * hz : 1.0;
}

/* the nodes and weights of [a, b] cut in 4, n points each, squared towards a flagged end */
static int gl_nodes(const gl_ctx *g, double a, double b, int sq_a, int sq_b, double *x, double *w)
{
    int m = 0;
    for (int q = 0; q < 4; ++q) {
        double lo = a + (b - a) * q / 4.0, hi = a + (b - a) * (q + 1) / 4.0;
        int ma = q == 0 && sq_a, mb = q == 3 && sq_b;
        double ulen = (ma || mb) ? sqrt(hi - lo) : hi - lo;
        for (int j = 0; j < g->n; ++j, ++m) {
            double u = 0.5 * ulen * (1.0 + g->xs[j]);
            w[m] = 0.5 * ulen * g->ws[j];
            if (ma)
                x[m] = lo + u * u, w[m] *= 2.0 * u;
            else if (mb)
                x[m] = hi - u * u, w[m] *= 2.0 * u;
            else
                x[m] = lo + u;
        }
    }
    return m;
}

static double gl_ray(const gl_ctx *g, double psi)
{
    double bc = g->eta < 1.0 ? asin(g->eta) : 0.5 * MF_PI, bh = atan2(g->c, g->s * cos(psi));
    double end = g->trans ? fmin(bc, fmin(bh, 0.5 * MF_PI)) : 0.5 * bh;
    if (g->trans && g->eta < 1.0 && gl_wtz(g, end, psi) > 0.0) { /* the transmission's horizon */
        double lo = 0.0, hi = end;
        for (int it = 0; it < 200 && hi - lo > 1e-16; ++it) {
            double mid = 0.5 * (lo + hi);
            if (gl_wtz(g, mid, psi) > 0.0)
                hi = mid;
            else
                lo = mid;
        }
        end = lo;
    }
    double bp[3] = {0.0, end, end};
    int sq[3] = {0, end == bc && g->eta < 1.0, 0}, nb = 2;
    if (bc < end)
        bp[1] = bc, bp[2] = end, sq[1] = 1, sq[2] = 0, nb = 3;
    double sum = 0.0, x[4 * 256], w[4 * 256];
    for (int p = 0; p + 1 < nb; ++p) {
        int m = gl_nodes(g, bp[p], bp[p + 1], sq[p], sq[p + 1], x, w);
        for (int j = 0; j < m; ++j)
            sum += w[j] * gl_point(g, x[j], psi);
    }
    return sum;
}

static double gl_eval(double alpha, double mu, double eta, int trans, int n)
{
    double xs[256], ws[256];
    CHECK(mf_quad_gauss_legendre(n, xs, ws) == MF_OK);
    gl_ctx g = {sqrt(1.0 - mu * mu), mu, eta, alpha, trans, n, xs, ws};
    double bp[64];
    int ev[64], nb = 0;
    bp[nb] = 0.0, ev[nb++] = 0;
    bp[nb] = 0.5 * MF_PI, ev[nb++] = 0;
    bp[nb] = MF_PI, ev[nb++] = 0;
    if (eta < 1.0) {
        double bc = asin(eta), cps[3] = {g.c / (g.s * tan(2.0 * bc)), g.c / (g.s * tan(bc)), -g.c * tan(bc) / g.s};
        for (int i = 0; i < 3; ++i)
            if (fabs(cps[i]) < 1.0)
                bp[nb] = acos(cps[i]), ev[nb++] = 1;
    }
    for (double d = 0.25 * alpha / g.s; d < 0.5 * MF_PI; d *= 2.0)
        bp[nb] = MF_PI - d, ev[nb++] = 0;
    for (int i = 1; i < nb; ++i)
        for (int k = i; k > 0 && bp[k] < bp[k - 1]; --k) {
            double t = bp[k];
            bp[k] = bp[k - 1], bp[k - 1] = t;
            int e = ev[k];
            ev[k] = ev[k - 1], ev[k - 1] = e;
        }
    double sum = 0.0, x[4 * 256], w[4 * 256];
    for (int p = 0; p + 1 < nb; ++p) {
        if (!(bp[p + 1] > bp[p]))
            continue;
        int m = gl_nodes(&g, bp[p], bp[p + 1], ev[p], ev[p + 1], x, w);
        for (int j = 0; j < m; ++j)
            sum += w[j] * gl_ray(&g, x[j]);
    }
    return 2.0 * sum;
}

/* mf_energy_dielectric_reference (the gate's reference) against the rule above at orders 48 and 96
 * per quarter panel, at the texel the old gate failed (alpha 0.5625, mu 0.25, eta 1/2.125; the
 * former references, whose panels did not end on the critical angle, were 7e-9 and 9e-9 off there)
 * and at points whose views sit on the kinks of E(mu) (mu = eta, sqrt(1 - eta^2), 2 eta
 * sqrt(1 - eta^2)) or graze; and the table's rule (mf_albedo_dielectric) against both.  Tolerances:
 * the reference's own bound plus the high-order rule's |Q96 - Q48| (its error estimate), plus 1e-13
 * for rounding (each rule sums ~10^6 terms of size <= 1); the table's rule within its own bound plus the
 * reference's. */
static void dielectric_reference_tir(void)
{
    const double pts[][3] = {{0.5625, 0.25, 1.0 / 2.125}, {0.5625, 0.75, 1.0 / 2.125}, {0.77, 0.125, 0.97},
                             {0.77, 0.125, 0.395}, {1.0, 0.5, 1.0 / 1.5}, {0.3, 0.6, 0.6}, {0.3, 0.8, 0.6},
                             {0.3, 0.96, 0.6}, {0.0625, 0.5, 1.0 / 1.5}, {0.3, 0.6, 1.5}};
    double worst_gl = 0.0, worst_tab = 0.0;
    for (size_t p = 0; p < sizeof pts / sizeof pts[0]; ++p) {
        double alpha = pts[p][0], mu = pts[p][1], eta = pts[p][2];
        mf_ndf ndf = mf_ndf_make(MF_NDF_GGX, alpha, alpha);
        mf_result rr, rt, ar, at;
        CHECK(mf_energy_dielectric_reference(ndf, MF_G2_JOINT, mu, eta, REF_TOL, &rr, &rt) == MF_OK);
        CHECK(mf_albedo_dielectric(ndf, MF_G2_JOINT, mu, eta, &ar, &at) == MF_OK);
        for (int q = 0; q < 2; ++q) {
            double lo = gl_eval(alpha, mu, eta, q, 48), hi = gl_eval(alpha, mu, eta, q, 96);
            const mf_result *ref = q ? &rt : &rr, *tab = q ? &at : &ar;
            double d = fabs(ref->val - hi), tol = ref->err + fabs(hi - lo) + 1e-13;
            double dt = fabs(tab->val - ref->val), tolt = tab->err + ref->err;
            if (!(d <= tol) || !(dt <= tolt))
                printf("dielectric reference alpha %g mu %g eta %.6g %s: reference %.15f (%.1e), GL96 %.15f (|GL96 - GL48| "
                       "%.1e), table %.15f (%.1e)\n",
                       alpha, mu, eta, q ? "E_T" : "E_R", ref->val, ref->err, hi, fabs(hi - lo), tab->val, tab->err);
            CHECK(d <= tol);
            CHECK(dt <= tolt);
            worst_gl = fmax(worst_gl, d / tol);
            worst_tab = fmax(worst_tab, dt / tolt);
        }
    }
    printf("dielectric reference near TIR: 10 points x (E_R, E_T): worst |ref - GL96| / tolerance %.3f, worst |table - ref| "
           "/ (both bounds) %.3f\n",
           worst_gl, worst_tab);
}

/* ---- the table's rule against the reference, within its own bound, near total internal reflection - */

/* One point: |rule - reference| <= rule bound + reference bound for E_R and E_T, and the rule's bound
 * <= 1e-9 (the target).  The tolerance is the sum of the two stated bounds and nothing else:
 * the reference (tolerance 1e-11, its bounds ~3e-13) is the arbiter, so any excess is the rule's
 * bound failing to bound its error.  A reference that ran out of intervals still returns its
 * estimate and bound (counted and printed). */
static void diel_point(mf_ndf_type t, double alpha, double mu, double eta, double *worst, int *count, int *nc)
{
    mf_ndf ndf = mf_ndf_make(t, alpha, alpha);
    mf_result r, tr, qr, qt;
    CHECK(mf_albedo_dielectric(ndf, MF_G2_JOINT, mu, eta, &r, &tr) == MF_OK);
    mf_status st = mf_energy_dielectric_reference(ndf, MF_G2_JOINT, mu, eta, 1e-11, &qr, &qt);
    CHECK(st == MF_OK || st == MF_ERR_NO_CONVERGENCE);
    *nc += st != MF_OK;
    double vr = fabs(r.val - qr.val) / (r.err + qr.err), vt = fabs(tr.val - qt.val) / (tr.err + qt.err);
    if (!(vr <= 1.0) || !(vt <= 1.0) || !(r.err <= 1e-9) || !(tr.err <= 1e-9))
        printf("dielectric rule %s alpha %g mu %.9g eta %.9g: E_R %.15f (%.1e) ref %.15f (%.1e) ratio %.3g; E_T %.15f (%.1e) "
               "ref %.15f (%.1e) ratio %.3g%s\n",
               t == MF_NDF_GGX ? "ggx" : "beckmann", alpha, mu, eta, r.val, r.err, qr.val, qr.err, vr, tr.val, tr.err, qt.val,
               qt.err, vt, st != MF_OK ? " (reference unconverged)" : "");
    CHECK(vr <= 1.0 && vt <= 1.0);
    CHECK(r.err <= 1e-9 && tr.err <= 1e-9);
    *worst = fmax(*worst, fmax(vr, vt));
    ++*count;
}

/* The rule's outer events in closed form (lib/src/mf_albedo.c, docs/math.md) against the domain
 * bounds they come from, written here from the geometry: at b_t the refraction through the
 * micro-normal h = cos(b) wo - sin(b) e1 (p = pi) is horizontal: wt.z < 0 for b < b_t, >= 0 for
 * b_t < b < b_c, when theta_o > b_c; otherwise wt.z < 0 up to b_c (the closed form's root is then
 * spurious, and the rule does not use it); at b_1 (b_2) the reflection through p = 0 (p = pi) grazes. */
static void diel_events(void)
{
    const double mus[] = {0.01, 0.125, 0.3, 0.6, 0.8};
    const double etas[] = {1.0 / 2.88, 0.47, 0.6, 0.9};
    double worst = 0.0;
    for (int m = 0; m < 5; ++m)
        for (int e = 0; e < 4; ++e) {
            double mu = mus[m], eta = etas[e], s = sqrt(1.0 - mu * mu), to = atan2(s, mu), bc = asin(eta);
            double d = 0.5 * MF_PI - to, bt = atan2(eta * sin(d), 1.0 - eta * cos(d));
            /* wt.z at (b, p = pi): h = (cos b s - sin b mu, 0, cos b mu + sin b s) */
            for (int side = -1; side <= 1; side += 2) {
                double b = bt * (1.0 + side * 1e-6);
                if (!(to > bc)) /* no root: the refraction at p = pi points down up to the critical angle */
                    b = bc * (1.0 - 1e-6);
                mf_vec3 wo = mf_vec3_make(s, 0.0, mu);
                mf_vec3 h = mf_vec3_make(cos(b) * s - sin(b) * mu, 0.0, cos(b) * mu + sin(b) * s);
                /* Snell in vector form [Walter 2007, Eq. 40]: wt = -wo / eta + (ci / eta - ct) h */
                double ci = mf_vec3_dot(wo, h), ct2 = 1.0 - (1.0 - ci * ci) / (eta * eta);
                CHECK(ct2 > 0.0);
                mf_vec3 wt = mf_vec3_sub(mf_vec3_scale(h, ci / eta - sqrt(fmax(ct2, 0.0))), mf_vec3_scale(wo, 1.0 / eta));
                /* below b_t the refracted ray points into the lower hemisphere, above it not */
                int down = to > bc ? side < 0 : 1;
                if (!(down == (wt.z < 0.0)))
                    printf("dielectric event b_t mu %g eta %g: wt.z %.3g at b %.9g (b_t %.9g, b_c %.9g)\n", mu, eta, wt.z, b, bt, bc);
                CHECK(down == (wt.z < 0.0));
            }
            double b1 = 0.5 * (0.5 * MF_PI - to), b2 = 0.5 * (0.5 * MF_PI + to);
            /* wr.z = mu cos 2b -+ s sin 2b at p = 0 (pi) */
            double r1 = mu * cos(2.0 * b1) - s * sin(2.0 * b1), r2 = mu * cos(2.0 * b2) + s * sin(2.0 * b2);
            worst = fmax(worst, fmax(fabs(r1), fabs(r2)));
            CHECK(fabs(r1) <= 1e-15 && fabs(r2) <= 1e-15);
        }
    printf("dielectric rule events: b_t separates wt.z < 0 from >= 0 at 1e-6; |wr.z| at b_1, b_2 <= %.1e\n", worst);
}

/* The rule against the reference: full = 1 runs the grid where it used to exceed its bound (6 alphas
 * x 9 mu x 7 eta, GGX and Beckmann: 756 points), the dense set near total internal reflection at 3
 * alphas and the grazing set (about 1 min of CPU, the slow test); full = 0 the points where it used to
 * fail and the dense set at one alpha (a few s). */
static void dielectric_rule(int full)
{
    double worst = 0.0;
    int count = 0, nc = 0;
    const double al[] = {0.001, 0.0625, 0.3, 0.5625, 0.77, 1.0};
    const double mus[] = {0.03, 0.125, 0.25, 0.5, 0.6, 0.75, 0.8, 0.96, 0.99};
    const double et[] = {1.0 / 2.88, 0.395, 0.47, 0.6, 2.0 / 3.0, 0.97, 1.5};
    if (full) {
        for (int n = 0; n < 2; ++n)
            for (int a = 0; a < 6; ++a)
                for (int m = 0; m < 9; ++m)
                    for (int e = 0; e < 7; ++e)
                        diel_point(n ? MF_NDF_BECKMANN : MF_NDF_GGX, al[a], mus[m], et[e], &worst, &count, &nc);
    } else {
        /* the worst points of the former rule (up to 4.6 and 33.8 times its bound) and of the first
         * version of this one (E_T 14.7 times at the first, E_R at the Beckmann grazing view) */
        const double pts[][4] = {{0, 1.0, 0.75, 1.0 / 2.88},   {0, 0.5625, 0.75, 1.0 / 2.88}, {0, 1.0, 0.5, 0.6},
                                 {0, 0.0625, 0.8, 0.6},         {0, 0.001, 0.5, 2.0 / 3.0},  {0, 0.0625, 0.25, 2.0 / 3.0},
                                 {0, 0.0625, 0.8, 0.47},        {0, 0.5625, 0.75, 0.47},     {0, 0.3, 0.75, 1.0 / 2.88},
                                 {1, 1.0, 1e-3, 1.5},           {1, 1.0, 1.745e-4, 1.5}};
        for (size_t i = 0; i < sizeof pts / sizeof pts[0]; ++i)
            diel_point(pts[i][0] ? MF_NDF_BECKMANN : MF_NDF_GGX, pts[i][1], pts[i][2], pts[i][3], &worst, &count, &nc);
    }
    /* dense near total internal reflection: the views on and 2e-3 either side of the kinks of E(mu)
     * (mu = eta, sqrt(1 - eta^2), 2 eta sqrt(1 - eta^2)), where the rule's events meet the critical
     * angle */
    const double etd[] = {1.0 / 2.88, 0.395, 0.47, 0.6, 2.0 / 3.0, 0.8, 0.97};
    const double ald[] = {0.5625, 0.0625, 1.0};
    for (int a = 0; a < (full ? 3 : 1); ++a)
        for (int e = 0; e < 7; ++e) {
            double eta = etd[e], mc = sqrt(1.0 - eta * eta), k[3] = {eta, mc, 2.0 * eta * mc};
            for (int i = 0; i < 3; ++i)
                for (int o = -1; o <= 1; ++o) {
                    double mu = k[i] + 2e-3 * o;
                    if (mu > 0.0 && mu <= 1.0)
                        diel_point(MF_NDF_GGX, ald[a], mu, eta, &worst, &count, &nc);
                }
        }
    /* grazing views (89.94 and 89.99 deg), where the events crowd within wo.z of b = 0 and pi/2 */
    if (full)
        for (int n = 0; n < 2; ++n)
            for (int a = 0; a < 3; ++a)
                for (int m = 0; m < 2; ++m)
                    for (int e = 0; e < 2; ++e)
                        diel_point(n ? MF_NDF_BECKMANN : MF_NDF_GGX, (double[]){1e-3, 0.3, 1.0}[a], m ? 1.745e-4 : 1e-3,
                                   e ? 1.5 : 0.47, &worst, &count, &nc);
    printf("dielectric rule vs reference%s: %d points x (E_R, E_T), worst |rule - ref| / (both bounds) %.3f, %d reference(s) "
           "unconverged\n",
           full ? " (full)" : "", count, worst, nc);
}

static void dfg_identity(void)
{
    const double f0s[] = {0.0, 0.04, 0.5, 1.0};
    for (int a = 0; a < 3; ++a)
        for (int t = 0; t < 3; ++t) {
            double alpha = (double[]){1e-3, 0.2, 0.9}[a], mu = (double[]){1.0, 0.5, 0.05}[t];
            mf_result s, b;
            CHECK(mf_energy_dfg(MF_NDF_GGX, MF_G2_JOINT, alpha, mu, &s, &b) == MF_OK);
            for (int k = 0; k < 4; ++k) {
                mf_microfacet m = {mf_ndf_make(MF_NDF_GGX, alpha, alpha), MF_G2_JOINT, {MF_FRESNEL_SCHLICK, f0s[k], 0, 0}};
                mf_result q;
                CHECK(mf_albedo_microfacet(&m, mf_vec3_make(sqrt(1 - mu * mu), 0, mu), &q) == MF_OK);
                double d = fabs(f0s[k] * s.val + b.val - q.val);
                /* the same quadrature nodes, different summation: within both bounds */
                if (!(d <= s.err + b.err + q.err))
                    printf("alpha %g mu %g F0 %g: %.15g vs %.15g\n", alpha, mu, f0s[k], f0s[k] * s.val + b.val, q.val);
                CHECK(d <= s.err + b.err + q.err);
            }
        }
    CHECK(fabs(mf_energy_favg_schlick(0.04) - (20 * 0.04 + 1) / 21) == 0.0);
    mf_result fc;
    CHECK(mf_energy_favg_conductor(1.5, 0.0, &fc) == MF_OK); /* k = 0: a dielectric, F_avg(1.5) = 0.0918 */
    CHECK(fc.val > 0.09 && fc.val < 0.094);
}

static void furnace(void)
{
    mf_table t;
    CHECK(mf_energy_kulla_conty_table(&t, MF_NDF_GGX, MF_G2_JOINT, 8, 8, NULL, NULL) == MF_OK);
    mf_check ch[8];
    int n = 0;
    mf_status st = mf_table_kind_gate(&t, NULL, NULL, ch, 8, &n);
    for (int i = 0; i < n; ++i)
        if (!ch[i].passed)
            printf("%s: worst %g at %s\n", ch[i].name, ch[i].worst, ch[i].worst_at);
    CHECK(st == MF_OK);
    /* a corrupted E_avg must fail the furnace */
    t.data[2] *= 1.001;
    CHECK(mf_table_kind_gate(&t, NULL, NULL, ch, 8, &n) == MF_ERR_CHECK_FAILED);
    mf_table_free(&t);
}

/* ---- the split of the dielectric compensation between reflection and transmission ---------------- */

/* F_avg of the exact dielectric: against the conductor routine with k = 0 (another Fresnel formula,
 * another integration, eta > 1 only) and the two sides' identity 1 - F_avg(1/eta) = (1 - F_avg(eta)) /
 * eta^2 (a uniform radiance L outside sends pi L (1 - F_avg(eta)) in; in equilibrium the radiance inside
 * is eta^2 L and sends pi eta^2 L (1 - F_avg(1/eta)) out).  Tolerance 1e-13: both are quadratures to
 * 1e-14 of smooth integrands (the kink at the critical angle mapped away). */
static void favg_dielectric(void)
{
    const double etas[] = {1.0, 1.002, 1.1, 1.5, 2.0, 2.88, 4.0};
    double worst = 0.0;
    for (int e = 0; e < 7; ++e) {
        mf_result f, fi, fc;
        CHECK(mf_energy_favg_dielectric(etas[e], &f) == MF_OK);
        CHECK(mf_energy_favg_dielectric(1.0 / etas[e], &fi) == MF_OK);
        CHECK(mf_energy_favg_conductor(etas[e], 0.0, &fc) == MF_OK);
        double d = fabs((1.0 - fi.val) - (1.0 - f.val) / (etas[e] * etas[e]));
        worst = fmax(worst, fmax(d, fabs(f.val - fc.val)));
        if (!(d <= 1e-13) || !(fabs(f.val - fc.val) <= 1e-13))
            printf("F_avg eta %g: %.16f (conductor k = 0: %.16f), 1/eta: %.16f, identity off by %.2e\n", etas[e], f.val, fc.val,
                   fi.val, d);
        CHECK(d <= 1e-13);
        CHECK(fabs(f.val - fc.val) <= 1e-13);
    }
    mf_result f;
    CHECK(mf_energy_favg_dielectric(1.5, &f) == MF_OK);
    printf("F_avg dielectric: F_avg(1.5) %.12f, F_avg(1/1.5) %.12f; worst identity / conductor difference %.2e (tolerance 1e-13)\n",
           f.val, 1.0 - (1.0 - f.val) / 2.25, worst);
    CHECK(mf_energy_favg_dielectric(0.0, &f) == MF_ERR_DOMAIN);
    CHECK(mf_energy_favg_dielectric(NAN, &f) == MF_ERR_DOMAIN);
}

/* 2 integral_0^1 E_t(mu) mu dmu by adaptive Gauss-Kronrod (mf_quad_adaptive, 1e-10 per panel) on panels
 * ending on the kinks of E_t(mu), found here from the geometry (eta < 1: mu = eta, sqrt(1 - eta^2),
 * 2 eta sqrt(1 - eta^2); docs/tables.md), each mapped by the cubic mu = a + (b - a)(3 u^2 - 2 u^3), flat
 * at both ends.  (The Gauss-Legendre rule of transmit_avg is not accurate enough at small alpha: its
 * |Q24 - Q16| understated its error 4 times at alpha 0.05, eta 1.33.)  *b: the rule's estimate plus the
 * largest albedo bound met. */
typedef struct {
    mf_ndf_type nt;
    double alpha, eta, a, len, maxerr;
} tavg_ctx;

static double tavg_f(double u, void *user)
{
    tavg_ctx *c = user;
    double mu = c->a + c->len * u * u * (3.0 - 2.0 * u), w = 6.0 * c->len * u * (1.0 - u);
    if (!(mu > 0.0) || !(w > 0.0))
        return 0.0;
    mf_result r, tr;
    CHECK(mf_albedo_dielectric(mf_ndf_make(c->nt, c->alpha, c->alpha), MF_G2_JOINT, fmin(mu, 1.0), c->eta, &r, &tr) == MF_OK);
    c->maxerr = fmax(c->maxerr, tr.err);
    return 2.0 * mu * w * tr.val;
}

static double transmit_avg_adaptive(mf_ndf_type nt, double alpha, double eta, double *b)
{
    double k[5] = {0.0, 1.0}, sum = 0.0;
    int n = 2;
    if (eta < 1.0) {
        double mc = sqrt(1.0 - eta * eta), c3[3] = {eta, mc, 2.0 * eta * mc};
        for (int i = 0; i < 3; ++i)
            if (c3[i] > 1e-6 && c3[i] < 1.0 - 1e-9)
                k[n++] = c3[i];
        for (int i = 1; i < n; ++i) /* insertion sort */
            for (int j = i; j > 0 && k[j] < k[j - 1]; --j) {
                double x = k[j];
                k[j] = k[j - 1], k[j - 1] = x;
            }
    }
    tavg_ctx c = {nt, alpha, eta, 0.0, 0.0, 0.0};
    *b = 0.0;
    for (int p = 0; p + 1 < n; ++p) {
        if (!(k[p + 1] > k[p]))
            continue;
        c.a = k[p], c.len = k[p + 1] - k[p];
        mf_result q;
        CHECK(mf_quad_adaptive(tavg_f, &c, 0.0, 1.0, 1e-10, 0.0, 400, &q) == MF_OK);
        sum += q.val;
        *b += q.err;
    }
    *b += c.maxerr;
    return sum;
}

/* The split [Kulla and Conty 2017] (mf_energy_dielectric_ms_split):
 *  - each side's fractions in [0, 1]; x + x' = 1 for the pair (t = (1 - F_avg) x);
 *  - the transmitted flux of the whole compensated BSDF balances, T(eta) = eta^2 T(1/eta), with the
 *    single scattering averaged by this file's own Gauss-Legendre rule; tolerance: that rule's
 *    |Q24 - Q16| and the albedo bounds, plus t times each E_avg bound;
 *  - three other splits one might write fail the same balance by far more than that tolerance (the
 *    test has power): x = 1/2 (the Fresnel average alone), eta^2 on the wrong side, and the transmitted
 *    fraction 1 - F_avg on both sides (the compensation split like a smooth interface's energy),
 *    each wherever it moves the averaged transmitted flux by more than 1e-6 (near eta = 1 and for
 *    nearly smooth surfaces they are nearly right);
 *  - the lobes pointwise: the reflected one symmetric in (mu_o, mu_i), the transmitted one reciprocal,
 *    K(eta; o -> i) = eta^2 K(1/eta; i -> o), to rounding (1e-14 relative).
 * One (ndf, alpha, eta) case per call; dielectric_split runs 4 GGX cases (CI) or, in the slow test
 * test_energy_dielectric_split, both NDFs over 6 alphas (1e-3 .. 1) x 6 etas (1.002 .. 2.88). */
static void split_case(mf_ndf_type nt, double alpha, double eta, int verbose, double *worst_ratio, double *worst_wrong_ratio)
{
    {
        double e2 = eta * eta;
        mf_result ea, ei, fa, fi;
        CHECK(mf_energy_dielectric_eavg(nt, MF_G2_JOINT, alpha, eta, &ea) == MF_OK);
        CHECK(mf_energy_dielectric_eavg(nt, MF_G2_JOINT, alpha, 1.0 / eta, &ei) == MF_OK);
        CHECK(mf_energy_favg_dielectric(eta, &fa) == MF_OK);
        CHECK(mf_energy_favg_dielectric(1.0 / eta, &fi) == MF_OK);
        double to, ti;
        CHECK(mf_energy_dielectric_ms_split(eta, ea.val, ei.val, fa.val, fi.val, &to) == MF_OK);
        CHECK(mf_energy_dielectric_ms_split(1.0 / eta, ei.val, ea.val, fi.val, fa.val, &ti) == MF_OK);
        CHECK(to >= 0.0 && to <= 1.0 && ti >= 0.0 && ti <= 1.0);
        CHECK_ABS(to / (1.0 - fa.val) + ti / (1.0 - fi.val), 1.0, 1e-15);
        CHECK_REL(to * (1.0 - ea.val), e2 * ti * (1.0 - ei.val), 1e-14);
        /* the balance of the whole BSDF, and of the three wrong splits */
        double wrong[3][2] = {{0.5 * (1.0 - fa.val), 0.5 * (1.0 - fi.val)}, {0, 0}, {1.0 - fa.val, 1.0 - fi.val}};
        {
            double a = (1.0 - fi.val) * (1.0 - ei.val) / e2, b = (1.0 - fa.val) * (1.0 - ea.val); /* eta^2 misplaced */
            wrong[1][0] = (1.0 - fa.val) * a / (a + b), wrong[1][1] = (1.0 - fi.val) * b / (a + b);
        }
        /* the averaged transmitted flux per side: E_t averaged plus the lobe's t (1 - E_avg); bound: the
         * average's plus t times the E_avg bound */
        double tbo, tbi, tao = transmit_avg_adaptive(nt, alpha, eta, &tbo), tai = transmit_avg_adaptive(nt, alpha, 1.0 / eta, &tbi);
        double fo = tao + to * (1.0 - ea.val), fin = tai + ti * (1.0 - ei.val);
        double tol = tbo + to * ea.err + e2 * (tbi + ti * ei.err), worst_wrong = INFINITY;
        for (int w = 0; w < 3; ++w) {
            double wfo = tao + wrong[w][0] * (1.0 - ea.val), wfi = tai + wrong[w][1] * (1.0 - ei.val);
            double wtol = tbo + wrong[w][0] * ea.err + e2 * (tbi + wrong[w][1] * ei.err);
            /* near eta = 1 or where almost nothing is missing a wrong split is nearly right: it must
             * fail wherever it moves the transmitted flux by more than 1e-6 */
            double moved = fabs(wrong[w][0] - to) * (1.0 - ea.val) + e2 * fabs(wrong[w][1] - ti) * (1.0 - ei.val);
            if (moved > 1e-6)
                worst_wrong = fmin(worst_wrong, fabs(wfo - e2 * wfi) / wtol);
        }
        if (verbose || !(fabs(fo - e2 * fin) <= tol) || !(worst_wrong > 10.0))
            printf("dielectric split %s alpha %g eta %g: E_avg %.9f / %.9f, t %.6f / %.6f; flux out %.12f, eta^2 x in %.12f: "
                   "|diff| / tolerance %.3g (tolerance %.2e); the wrong splits' smallest ratio %.3g\n",
                   nt == MF_NDF_GGX ? "ggx" : "beckmann", alpha, eta, ea.val, ei.val, to, ti, fo, e2 * fin,
                   fabs(fo - e2 * fin) / tol, tol, worst_wrong);
        *worst_ratio = fmax(*worst_ratio, fabs(fo - e2 * fin) / tol);
        *worst_wrong_ratio = fmin(*worst_wrong_ratio, worst_wrong);
        CHECK(fabs(fo - e2 * fin) <= tol);
        CHECK(worst_wrong > 10.0);
        /* the lobes pointwise */
        for (int p = 0; p < 3; ++p) {
            double muo = (double[]){0.9, 0.3, 0.05}[p], mui = (double[]){0.2, 0.7, 0.99}[p];
            mf_result ro, tro, ri, tri, rx, trx, rix, trix;
            mf_ndf ndf = mf_ndf_make(nt, alpha, alpha);
            CHECK(mf_albedo_dielectric(ndf, MF_G2_JOINT, muo, eta, &ro, &tro) == MF_OK);      /* E(mu_o), outside */
            CHECK(mf_albedo_dielectric(ndf, MF_G2_JOINT, mui, eta, &rx, &trx) == MF_OK);      /* E(mu_i), outside */
            CHECK(mf_albedo_dielectric(ndf, MF_G2_JOINT, mui, 1.0 / eta, &ri, &tri) == MF_OK); /* E_inv(mu_i) */
            CHECK(mf_albedo_dielectric(ndf, MF_G2_JOINT, muo, 1.0 / eta, &rix, &trix) == MF_OK);
            double eo = ro.val + tro.val, ex = rx.val + trx.val, eiv = ri.val + tri.val, eiv_o = rix.val + trix.val;
            CHECK_REL(mf_energy_kc_lobe(1.0 - to, eo, ex, ea.val), mf_energy_kc_lobe(1.0 - to, ex, eo, ea.val), 1e-15);
            /* light from mu_o outside into mu_i inside, and back */
            double k_out = mf_energy_kc_lobe(to, eo, eiv, ei.val), k_in = mf_energy_kc_lobe(ti, eiv, eo, ea.val);
            /* not 0 = 0: wherever both missing energies exceed their bounds the lobe is positive (at
             * alpha 1e-3 E may round to 1 or above within its bound, and the lobe is then 0) */
            if (1.0 - eo > ro.err + tro.err && 1.0 - eiv > ri.err + tri.err)
                CHECK(k_out > 0.0);
            CHECK(k_out >= 0.0 && k_in >= 0.0);
            CHECK_REL(k_out, e2 * k_in, 1e-14);
            (void)eiv_o;
        }
    }
}

static void dielectric_split(int full)
{
    double worst = 0.0, wrong = INFINITY;
    int count = 0;
    if (!full) {
        const double cases[][2] = {{0.3, 1.5}, {1.0, 1.5}, {0.6, 2.88}, {0.05, 1.33}};
        for (int c = 0; c < 4; ++c, ++count)
            split_case(MF_NDF_GGX, cases[c][0], cases[c][1], 1, &worst, &wrong);
    } else { /* the slow test: both NDFs over alpha 1e-3 .. 1 and eta 1.002 .. 2.88 (the table's range) */
        const double al[] = {1e-3, 0.01, 0.1, 0.3, 0.6, 1.0}, et[] = {1.002, 1.05, 1.33, 1.5, 2.0, 2.88};
        for (int n = 0; n < 2; ++n)
            for (int a = 0; a < 6; ++a)
                for (int e = 0; e < 6; ++e, ++count)
                    split_case(n ? MF_NDF_BECKMANN : MF_NDF_GGX, al[a], et[e], 0, &worst, &wrong);
    }
    printf("dielectric split: %d (ndf, alpha, eta) cases, worst |T(eta) - eta^2 T(1/eta)| / tolerance %.3g; the wrong splits "
           "fail by at least %.3g times their tolerance\n", count, worst, wrong);
    if (full)
        return;
    double t;
    CHECK(mf_energy_dielectric_ms_split(1.5, 1.5, 0.9, 0.1, 0.6, &t) == MF_ERR_DOMAIN);
    CHECK(mf_energy_dielectric_ms_split(1.5, 0.9, 0.9, 0.1, -0.1, &t) == MF_ERR_DOMAIN);
    /* no energy missing inside: the balance forbids transmitting the outside's compensation */
    CHECK(mf_energy_dielectric_ms_split(1.5, 0.9, 1.0, 0.1, 0.6, &t) == MF_OK && t == 0.0);
}

/* the gate of a 2 x 2 x 2 table computed in memory: diel_split passes; E_avg_inv of one column 1e-6
 * high (100 times its bound, about 1e-8) fails it (and the furnace) */
static void dielectric_split_gate(void)
{
    mf_table t;
    CHECK(mf_energy_dielectric_table(&t, MF_NDF_GGX, MF_G2_JOINT, 2, 2, 2, NULL, NULL) == MF_OK);
    mf_check ch[8];
    int n = 0;
    mf_status st = mf_table_kind_gate(&t, NULL, NULL, ch, 8, &n);
    int split = -1;
    for (int i = 0; i < n; ++i) {
        if (!strcmp(ch[i].name, "diel_split"))
            split = i;
        if (!ch[i].passed)
            printf("%s: worst %g at %s\n", ch[i].name, ch[i].worst, ch[i].worst_at);
    }
    CHECK(st == MF_OK && split >= 0);
    if (split >= 0)
        printf("dielectric gate 2^3: diel_split worst %.3g of its bound at %s\n", ch[split].worst, ch[split].worst_at);
    for (int i = 0; i < 2; ++i) /* column (j 0, k 0), both mu, the inside's E_avg */
        t.data[i * MF_DIELECTRIC_NFIELDS + 12] += 1e-6;
    st = mf_table_kind_gate(&t, NULL, NULL, ch, 8, &n);
    CHECK(st == MF_ERR_CHECK_FAILED && split >= 0 && split < n && !ch[split].passed);
    if (split >= 0 && split < n)
        printf("dielectric gate 2^3, E_avg_inv + 1e-6: diel_split %s, worst %.3g at %s\n", ch[split].passed ? "pass" : "fail",
               ch[split].worst, ch[split].worst_at);
    mf_table_free(&t);
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "dielectric-full")) { /* the slow test: the rule's whole grid */
        diel_events();
        dielectric_rule(1);
        MF_TEST_MAIN_END();
    }
    if (argc > 1 && !strcmp(argv[1], "split-full")) { /* the slow test: the split over the table's range */
        favg_dielectric();
        dielectric_split(1);
        MF_TEST_MAIN_END();
    }
    albedo_vs_reference();
    charlie_vs_reference();
    dielectric();
    dielectric_reference_tir();
    diel_events();
    dielectric_rule(0);
    dfg_identity();
    furnace();
    favg_dielectric();
    dielectric_split(0);
    dielectric_split_gate();
    MF_TEST_MAIN_END();
}
