/* mf_walk.c -- the random walk on the Smith microsurface (see mf_walk.h). */
#include "mfkit/mf_walk.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_smith.h"

#include <string.h>

static int walk_ndf_ok(mf_ndf ndf)
{
    return (ndf.type == MF_NDF_GGX || ndf.type == MF_NDF_BECKMANN) && ndf.alpha_x > 0.0 && ndf.alpha_y > 0.0
           && isfinite(ndf.alpha_x) && isfinite(ndf.alpha_y);
}

/* ---- Beckmann's visible slopes ------------------------------------------------------------------
 * In the space stretched to alpha = 1 and turned so that the view is v = (s, 0, c) (s >= 0), the
 * visible slopes (x, y) of v have the density (c - x s) exp(-x^2 - y^2) / pi on x < b = c / s (the
 * micro-normal (-x, -y, 1) faces v), up to the normalisation [Heitz and d'Eon 2014, "Importance
 * sampling microfacet-based BSDFs using the distribution of visible normals": the slope along the view
 * by inverting its CDF, the other one independent and Gaussian].  Unnormalised CDF along the view:
 *   F(x) = c erfc(-x) / 2 + s exp(-x^2) / (2 sqrt(pi)),  F'(x) = (c - x s) exp(-x^2) / sqrt(pi). */

#define WALK_SQRT_PI 1.77245385090551602729816748334

/* erfinv(x), |x| < 1, to about 1e-7 relative [Giles 2010, "Approximating the erfinv function",
 * the single-precision polynomials]: the Newton iterations' starting point */
static double erfinv_start(double x)
{
    double w = -log((1.0 - x) * (1.0 + x)), p;
    if (w < 5.0) {
        w -= 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    return p * x;
}

static double beck_cdf(double c, double s, double x)
{
    return 0.5 * c * erfc(-x) + 0.5 * s * exp(-x * x) / WALK_SQRT_PI;
}

/* x with F(x) = u F(b), u in (0, 1): Newton on log F, kept inside a bisection bracket.  Used for
 * b >= -1, where F has no cancellation worth a digit (its two terms differ by at least a factor 1 /
 * 0.76 at x = b = -1, more below). */
static double beck_slope_inv(double c, double s, double u)
{
    double b = s > 0.0 ? c / s : INFINITY;
    double hi = fmin(b, 10.0); /* F(10) = c to 1e-45 */
    double x0 = erfinv_start(2.0 * u - 1.0); /* the quantile for a normal view (c = 1) */
    double lo = fmin(x0, hi) - 0.5;
    double target = u * beck_cdf(c, s, hi);
    while (beck_cdf(c, s, lo) > target && lo > -40.0)
        lo -= 1.0;
    double x = x0 > lo && x0 < hi ? x0 : 0.5 * (lo + hi), lt = log(target);
    for (int it = 0; it < 200 && hi - lo > 1e-15 * (1.0 + fabs(x)); ++it) {
        double f = beck_cdf(c, s, x);
        if (f > target)
            hi = x;
        else
            lo = x;
        double d = (c - x * s) * exp(-x * x) / WALK_SQRT_PI;
        double xn = (f > 0.0 && d > 0.0) ? x - f * (log(f) - lt) / d : NAN;
        if (xn >= lo && xn <= hi) {
            int done = fabs(xn - x) <= 1e-14 * (1.0 + fabs(x)); /* Newton converges quadratically */
            x = xn;
            if (done)
                break;
        } else {
            x = 0.5 * (lo + hi);
        }
    }
    return x;
}

/* y with (1 + erf(y)) / 2 = u (a normal of variance 1/2), u in (0, 1): solve erfc(t) = 2 min(u, 1 - u)
 * for t >= 0 by Newton on log erfc in a bisection bracket. */
static double half_normal_inv(double u)
{
    double p = 2.0 * fmin(u, 1.0 - u), lo = 0.0, hi = 27.0, lp = log(p);
    double t = fmin(fmax(fabs(erfinv_start(1.0 - p)), 0.0), 26.0);
    for (int it = 0; it < 200 && hi - lo > 1e-15 * (1.0 + t); ++it) {
        double e = erfc(t);
        if (e > p)
            lo = t;
        else
            hi = t;
        double d = -2.0 * exp(-t * t) / WALK_SQRT_PI;
        double tn = (e > 0.0) ? t - e * (log(e) - lp) / d : NAN;
        if (tn >= lo && tn <= hi) {
            int done = fabs(tn - t) <= 1e-14 * (1.0 + t);
            t = tn;
            if (done)
                break;
        } else {
            t = 0.5 * (lo + hi);
        }
    }
    return u < 0.5 ? -t : t;
}

/* the visible normal from the stretched, turned view (vs), its slopes (x along the view, y across) */
static mf_vec3 beck_normal(mf_ndf ndf, mf_vec3 vs, double x, double y)
{
    double r = sqrt(vs.x * vs.x + vs.y * vs.y);
    double cp = r > 0.0 ? vs.x / r : 1.0, sp = r > 0.0 ? vs.y / r : 0.0;
    double sx = ndf.alpha_x * (cp * x - sp * y), sy = ndf.alpha_y * (sp * x + cp * y);
    return mf_vec3_normalize(mf_vec3_make(-sx, -sy, 1.0));
}

static mf_vec3 beck_stretch(mf_ndf ndf, mf_vec3 v, double *c, double *s)
{
    mf_vec3 vs = mf_vec3_normalize(mf_vec3_make(ndf.alpha_x * v.x, ndf.alpha_y * v.y, v.z));
    *c = vs.z;
    *s = sqrt(fmax(0.0, vs.x * vs.x + vs.y * vs.y));
    return vs;
}

static double clamp_open(double u) { return fmin(fmax(u, 0x1.0p-54), 1.0 - 0x1.0p-54); }

mf_vec3 mf_walk_sample_vndf(mf_ndf ndf, mf_vec3 v, const double u[2])
{
    if (!walk_ndf_ok(ndf) || !mf_vec3_isfinite(v) || !(v.z > -1.0))
        return mf_vec3_make(NAN, NAN, NAN);
    if (ndf.type == MF_NDF_BECKMANN) {
        double c, s;
        mf_vec3 vs = beck_stretch(ndf, v, &c, &s);
        if (c < -s) /* b < -1: mf_walk_sample_vndf_rng's rejection sampler */
            return mf_vec3_make(NAN, NAN, NAN);
        return beck_normal(ndf, vs, beck_slope_inv(c, s, clamp_open(u[0])), half_normal_inv(clamp_open(u[1])));
    }
    /* [Dupuy and Benyoub 2023]: stretch to alpha = 1, where the visible normals of v are
     * normalize(v + c) with c uniform on the cap of the unit sphere above z = -v.z (a mirror sphere
     * reflects uniformly; the cap keeps m.z > 0), then unstretch the normal */
    mf_vec3 vs = mf_vec3_normalize(mf_vec3_make(ndf.alpha_x * v.x, ndf.alpha_y * v.y, v.z));
    double z = (1.0 - u[0]) * (1.0 + vs.z) - vs.z;
    double r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * MF_PI * u[1];
    mf_vec3 h = mf_vec3_make(vs.x + r * cos(phi), vs.y + r * sin(phi), vs.z + z);
    mf_vec3 m = mf_vec3_make(ndf.alpha_x * h.x, ndf.alpha_y * h.y, fmax(0.0, h.z));
    double len = mf_vec3_length(m);
    return len > 0.0 ? mf_vec3_scale(m, 1.0 / len) : mf_vec3_make(0.0, 0.0, 1.0);
}

mf_vec3 mf_walk_sample_vndf_rng(mf_ndf ndf, mf_vec3 v, mf_pcg32 *rng)
{
    double uu[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
    if (ndf.type != MF_NDF_BECKMANN || !walk_ndf_ok(ndf) || !mf_vec3_isfinite(v) || !(v.z > -1.0))
        return mf_walk_sample_vndf(ndf, v, uu);
    double c, s;
    mf_vec3 vs = beck_stretch(ndf, v, &c, &s);
    if (c >= -s)
        return mf_walk_sample_vndf(ndf, v, uu);
    /* b = c / s < -1: with y' = b - x > 0 the density along the view is proportional to
     * y' exp(-(b - y')^2) = exp(-b^2) y' exp(-2 |b| y') exp(-y'^2): a Gamma(2, 2 |b|) proposal accepted
     * with probability exp(-y'^2) (at least about 0.45 for |b| >= 1) */
    double b = c / s, lambda = -2.0 * b, y;
    for (;;) {
        double u1 = 1.0 - mf_pcg32_next_double(rng), u2 = 1.0 - mf_pcg32_next_double(rng);
        y = -log(u1 * u2) / lambda;
        if (mf_pcg32_next_double(rng) < exp(-y * y))
            break;
    }
    return beck_normal(ndf, vs, b - y, half_normal_inv(clamp_open(uu[1])));
}

/* The free path from u = C1(h) along w (Heitz et al. 2016, the height distribution of the next hit):
 * returns 1 when the ray leaves the surface, else 0 with *u at the hit. */
static int walk_height(mf_ndf ndf, mf_vec3 w, double *u, mf_pcg32 *rng)
{
    double one_minus_U = 1.0 - mf_pcg32_next_double(rng); /* in (0, 1] */
    if (w.z > 0.0) {
        double lam = mf_smith_lambda(ndf, w);
        double g1 = lam > 0.0 ? pow(*u, lam) : 1.0; /* G1(w, h) = C1(h)^Lambda(w) */
        if (one_minus_U <= g1)
            return 1;
        *u = fmin(1.0, *u * pow(one_minus_U, -1.0 / lam));
        return 0;
    }
    if (w.z < 0.0) {
        double lam = mf_smith_lambda(ndf, mf_vec3_scale(w, -1.0)); /* Lambda(w) = -1 - Lambda(-w) */
        *u *= pow(one_minus_U, 1.0 / (1.0 + lam));
    }
    return 0; /* a horizontal ray meets the surface where it is */
}

static int walk_args_ok(mf_ndf ndf, mf_vec3 wo, int max_bounces)
{
    return walk_ndf_ok(ndf) && mf_vec3_isfinite(wo) && wo.z > 0.0 && fabs(mf_vec3_length(wo) - 1.0) < 1e-9
           && max_bounces >= 1;
}

static mf_vec3 reflect_about(mf_vec3 v, mf_vec3 m, double c) /* v leaving, c = v.m */
{
    return mf_vec3_sub(mf_vec3_scale(m, 2.0 * c), v);
}

mf_status mf_walk_conductor(mf_ndf ndf, mf_vec3 wo, const mf_fresnel *f, int nf, int max_bounces, mf_pcg32 *rng,
                            mf_walk_path *out, double *weight)
{
    out->bounces = 0;
    out->side = 0;
    out->w = mf_vec3_make(NAN, NAN, NAN);
    if (!walk_args_ok(ndf, wo, max_bounces) || nf < 0 || nf > MF_WALK_MAX_CHANNELS || (nf > 0 && (!f || !weight)))
        return MF_ERR_DOMAIN;
    for (int c = 0; c < nf; ++c)
        weight[c] = 1.0;
    mf_vec3 w = mf_vec3_scale(wo, -1.0);
    double u = 1.0;
    for (;;) {
        if (walk_height(ndf, w, &u, rng)) {
            out->side = 1;
            out->w = w;
            return MF_OK;
        }
        if (out->bounces == max_bounces)
            return MF_OK; /* side 0: stopped */
        ++out->bounces;
        mf_vec3 v = mf_vec3_scale(w, -1.0);
        mf_vec3 m = mf_walk_sample_vndf_rng(ndf, v, rng);
        double c = fmax(0.0, mf_vec3_dot(v, m));
        for (int k = 0; k < nf; ++k)
            weight[k] *= mf_fresnel_eval(f[k], c);
        w = mf_vec3_normalize(reflect_about(v, m, c));
    }
}

mf_status mf_walk_dielectric(mf_ndf ndf, double eta, mf_vec3 wo, int max_bounces, mf_pcg32 *rng,
                             mf_walk_path *out)
{
    out->bounces = 0;
    out->side = 0;
    out->w = mf_vec3_make(NAN, NAN, NAN);
    if (!walk_args_ok(ndf, wo, max_bounces) || !(eta > 0.0) || !isfinite(eta))
        return MF_ERR_DOMAIN;
    /* w and u are in the frame of the current side (z up, into the medium the ray travels in) */
    mf_vec3 w = mf_vec3_scale(wo, -1.0);
    double u = 1.0, e = eta;
    int side = 1;
    for (;;) {
        if (walk_height(ndf, w, &u, rng)) {
            out->side = side;
            out->w = side > 0 ? w : mf_vec3_scale(w, -1.0);
            return MF_OK;
        }
        if (out->bounces == max_bounces)
            return MF_OK;
        ++out->bounces;
        mf_vec3 v = mf_vec3_scale(w, -1.0);
        mf_vec3 m = mf_walk_sample_vndf_rng(ndf, v, rng);
        double c = fmax(0.0, mf_vec3_dot(v, m));
        double fr = mf_fresnel_dielectric(e, c);
        if (mf_pcg32_next_double(rng) < fr) {
            w = mf_vec3_normalize(reflect_about(v, m, c));
            continue;
        }
        /* refraction [Walter 2007, Eq. 40]: wt = -v / e + (c / e - cos_t) m, then the other side's frame:
         * the same microsurface upside down (h -> -h, u -> 1 - u), directions negated, eta inverted */
        double cos_t = sqrt(fmax(0.0, 1.0 - (1.0 - c * c) / (e * e)));
        mf_vec3 wt = mf_vec3_add(mf_vec3_scale(v, -1.0 / e), mf_vec3_scale(m, c / e - cos_t));
        w = mf_vec3_normalize(mf_vec3_scale(wt, -1.0));
        u = 1.0 - u;
        e = 1.0 / e;
        side = -side;
    }
}

mf_status mf_walk_dielectric_split(mf_ndf ndf, double eta, long walks, int max_bounces, uint64_t seed, uint64_t stream,
                                   mf_walk_split *out)
{
    memset(out, 0, sizeof *out);
    out->t = out->t_se = out->e1 = NAN;
    if (!walk_ndf_ok(ndf) || !(eta > 0.0) || !isfinite(eta) || walks < 1 || max_bounces < 1)
        return MF_ERR_DOMAIN;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, stream);
    for (long i = 0; i < walks; ++i) {
        double mu = sqrt(1.0 - mf_pcg32_next_double(&rng)); /* density 2 mu on (0, 1] */
        mf_walk_path p;
        mf_status st = mf_walk_dielectric(ndf, eta, mf_vec3_make(sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0, mu), max_bounces,
                                          &rng, &p);
        if (st != MF_OK)
            return st;
        ++out->walks;
        if (p.side == 0)
            ++out->stopped;
        else if (p.bounces == 1) {
            ++out->single;
            out->single_trans += p.side < 0;
        } else {
            ++out->ms;
            out->ms_trans += p.side < 0;
        }
    }
    out->e1 = (double)out->single / (double)out->walks;
    if (out->ms > 0) {
        double n = (double)out->ms, p = ((double)out->ms_trans + 0.5) / (n + 1.0);
        out->t = (double)out->ms_trans / n;
        out->t_se = sqrt(p * (1.0 - p) / n);
    }
    return MF_OK;
}

/* ---- single scattering by quadrature ------------------------------------------------------------ */

/* B(a, b) = Gamma(a) Gamma(b) / Gamma(a + b) for a, b >= 1 */
static double beta_fn(double a, double b)
{
    if (isinf(a) || isinf(b))
        return 0.0;
    return exp(lgamma(a) + lgamma(b) - lgamma(a + b));
}

static void single_point(mf_ndf ndf, mf_vec3 wo, double lam_o, double eta, const double uu[2], double *r, double *t)
{
    mf_vec3 m = mf_walk_sample_vndf(ndf, wo, uu);
    double c = fmax(0.0, mf_vec3_dot(wo, m));
    double fr = eta > 0.0 ? mf_fresnel_dielectric(eta, c) : 1.0;
    *r = *t = 0.0;
    mf_vec3 wi = reflect_about(wo, m, c);
    if (wi.z > 0.0 && fr > 0.0)
        *r = fr * (1.0 + lam_o) / (1.0 + lam_o + mf_smith_lambda(ndf, mf_vec3_normalize(wi)));
    if (eta > 0.0 && fr < 1.0) {
        double cos_t = sqrt(fmax(0.0, 1.0 - (1.0 - c * c) / (eta * eta)));
        mf_vec3 wt = mf_vec3_add(mf_vec3_scale(wo, -1.0 / eta), mf_vec3_scale(m, c / eta - cos_t));
        if (wt.z < 0.0) {
            double lam_t = mf_smith_lambda(ndf, mf_vec3_normalize(mf_vec3_scale(wt, -1.0)));
            *t = (1.0 - fr) * (1.0 + lam_o) * beta_fn(1.0 + lam_o, 1.0 + lam_t);
        }
    }
}

static mf_status single_rule(mf_ndf ndf, mf_vec3 wo, double eta, int n, double *r, double *t)
{
    enum { NG = 20 };
    double x[NG], w[NG];
    if (mf_quad_gauss_legendre(NG, x, w) != MF_OK)
        return MF_ERR_INTERNAL;
    double lam_o = mf_smith_lambda(ndf, wo), h = 1.0 / n;
    double sr = 0.0, st = 0.0;
    for (int i = 0; i < n; ++i)
        for (int a = 0; a < NG; ++a) {
            double u0 = (i + 0.5 * (1.0 + x[a])) * h, wa = 0.5 * h * w[a];
            double rr = 0.0, tt = 0.0;
            for (int j = 0; j < n; ++j)
                for (int b = 0; b < NG; ++b) {
                    double uu[2] = {u0, (j + 0.5 * (1.0 + x[b])) * h}, pr, pt;
                    single_point(ndf, wo, lam_o, eta, uu, &pr, &pt);
                    rr += 0.5 * h * w[b] * pr;
                    tt += 0.5 * h * w[b] * pt;
                }
            sr += wa * rr;
            st += wa * tt;
        }
    *r = sr;
    *t = st;
    return MF_OK;
}

mf_status mf_walk_single(mf_ndf ndf, double mu, double eta, int n, mf_result *r1, mf_result *t1)
{
    r1->val = r1->err = t1->val = t1->err = NAN;
    if (!walk_ndf_ok(ndf) || !(mu > 0.0 && mu <= 1.0) || !(eta >= 0.0) || !isfinite(eta) || n < 2 || n % 2)
        return MF_ERR_DOMAIN;
    mf_vec3 wo = mf_vec3_make(sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0, mu);
    double r, t, r2, t2;
    mf_status st = single_rule(ndf, wo, eta, n, &r, &t);
    if (st == MF_OK)
        st = single_rule(ndf, wo, eta, n / 2, &r2, &t2);
    if (st != MF_OK)
        return st;
    r1->val = r;
    t1->val = t;
    r1->err = fabs(r - r2);
    t1->err = fabs(t - t2);
    return MF_OK;
}
