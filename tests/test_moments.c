/* test_moments.c -- LEAN/LEADR slope moments, Hery bump roughness, symmetric 2x2 eigen-solver and
 * Toksvig (mf_moments.h), with docs/math.md, corrections C-N4, C-N5, C-H1, C-H2, C-H5, C-H6. */
#include "mf_test.h"
#include "mfkit/mf_moments.h"
#include "mfkit/mf_rng.h"

#include <float.h>

/* ---- analytic height fields: sums of sine waves plus a plane ----------------------------------
 * h(x, y) = sum_k A_k sin(2 pi (kx_k x + ky_k y) + ph_k) + gx x + gy y on the unit square.
 * Over a full period (an N x N grid with N > 2 |k| and no k_i +- k_j = 0 mod N) the grid means are
 * exact: E[cos^2] = 1/2, E[cos_i cos_j] = 0 (i != j), E[cos] = 0, so
 *   E[h_x] = gx,  E[h_x^2] = gx^2 + sum_k (2 pi A_k kx_k)^2 / 2,
 *   E[h_x h_y] = gx gy + sum_k (2 pi A_k)^2 kx_k ky_k / 2. */
typedef struct wave {
    double a, kx, ky, ph;
} wave;

typedef struct height_field {
    int n;
    wave w[3];
    double gx, gy;
} height_field;

static void hf_gradient(const height_field *f, double x, double y, double *hx, double *hy)
{
    *hx = f->gx;
    *hy = f->gy;
    for (int k = 0; k < f->n; ++k) {
        double c = cos(2 * MF_PI * (f->w[k].kx * x + f->w[k].ky * y) + f->w[k].ph);
        *hx += 2 * MF_PI * f->w[k].a * f->w[k].kx * c;
        *hy += 2 * MF_PI * f->w[k].a * f->w[k].ky * c;
    }
}

/* the unit normal of the height field, as a normal map would store it */
static mf_vec3 hf_normal(const height_field *f, double x, double y)
{
    double hx, hy;
    hf_gradient(f, x, y, &hx, &hy);
    return mf_vec3_normalize(mf_vec3_make(-hx, -hy, 1.0));
}

static mf_slope_moments hf_exact(const height_field *f)
{
    mf_slope_moments m = {f->gx, f->gy, f->gx * f->gx, f->gx * f->gy, f->gy * f->gy};
    for (int k = 0; k < f->n; ++k) {
        double s = 2 * MF_PI * f->w[k].a;
        m.m_xx += 0.5 * s * s * f->w[k].kx * f->w[k].kx;
        m.m_xy += 0.5 * s * s * f->w[k].kx * f->w[k].ky;
        m.m_yy += 0.5 * s * s * f->w[k].ky * f->w[k].ky;
    }
    return m;
}

/* box filter of the moments of the sampled normals over the N x N grid of cell centres */
static mf_slope_moments hf_sampled(const height_field *f, int n)
{
    mf_slope_moments acc = {0, 0, 0, 0, 0};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            mf_slope_moments m = mf_moments_from_normal(hf_normal(f, (i + 0.5) / n, (j + 0.5) / n));
            mf_moments_accumulate(&acc, &m, 1.0 / ((double)n * n));
        }
    return acc;
}

/* |a - b| <= tol * scale for every field */
#define CHECK_MOMENTS(a, b, tol, scale)                                                                          \
    do {                                                                                                     \
        CHECK_ABS((a).mean_x, (b).mean_x, (tol) * (scale));                                                  \
        CHECK_ABS((a).mean_y, (b).mean_y, (tol) * (scale));                                                  \
        CHECK_ABS((a).m_xx, (b).m_xx, (tol) * (scale) * (scale));                                            \
        CHECK_ABS((a).m_xy, (b).m_xy, (tol) * (scale) * (scale));                                            \
        CHECK_ABS((a).m_yy, (b).m_yy, (tol) * (scale) * (scale));                                            \
    } while (0)

static const height_field field_a = {3, {{0.02, 1, 0, 0.3}, {0.01, 2, 3, 1.1}, {0.004, -4, 1, 2.0}}, 0.15, -0.05};
static const height_field field_b = {2, {{0.015, 0, 2, 0.7}, {0.006, 3, -2, 0.2}}, -0.1, 0.2};

static void test_lean_moments(void)
{
    /* LEAN Eq. 3-5 on sampled normals vs the exact moments of the height field.  N = 64 cells:
     * sums of 4096 terms of size <= 0.3^2, tolerance 1e-14 (~50 eps of the slope scale 0.3). */
    mf_slope_moments ex = hf_exact(&field_a), sm = hf_sampled(&field_a, 64);
    CHECK_MOMENTS(sm, ex, 1e-14, 0.3);
    mf_gaussian_slopes g = mf_moments_to_gaussian(&sm);
    CHECK(mf_gaussian_valid(&g));
    double s1 = 2 * MF_PI * 0.02, s2 = 2 * MF_PI * 0.01 * 2, s3 = 2 * MF_PI * 0.004 * 4;
    CHECK_ABS(g.var_x, 0.5 * (s1 * s1 + s2 * s2 + s3 * s3), 1e-14);
    CHECK_ABS(g.mean_x, 0.15, 1e-15);

    /* correction C-N4: LEAN's B = n.xy/n.z is minus the height gradient; mfkit (LEADR) mean = -B. */
    mf_vec3 n = hf_normal(&field_a, 0.3, 0.7);
    double hx, hy;
    hf_gradient(&field_a, 0.3, 0.7, &hx, &hy);
    double bx = n.x / n.z, by = n.y / n.z; /* LEAN Eq. 3 as printed */
    mf_slope_moments mn = mf_moments_from_normal(n);
    CHECK_ABS(mn.mean_x, hx, 4 * DBL_EPSILON);
    CHECK_ABS(mn.mean_y, hy, 4 * DBL_EPSILON);
    CHECK_ABS(bx, -hx, 4 * DBL_EPSILON);
    mf_slope_moments ml = mf_moments_from_lean(bx, by, bx * bx, bx * by, by * by);
    CHECK(ml.mean_x == -bx && ml.mean_y == -by && ml.m_xy == bx * by);
    /* the mesonormal [Dupuy 2013, Eq. 11] of the filtered moments is the mean plane's normal
     * (-gx, -gy, 1); taking LEAN's B as the mean would tilt it the other way */
    mf_vec3 plane = mf_vec3_normalize(mf_vec3_make(-0.15, 0.05, 1.0));
    mf_vec3 meso = mf_gaussian_mesonormal(&g);
    CHECK_REL(mf_vec3_dot(meso, plane), 1.0, 1e-15);
    mf_gaussian_slopes wrong = g;
    wrong.mean_x = -g.mean_x;
    wrong.mean_y = -g.mean_y;
    CHECK(mf_vec3_dot(mf_gaussian_mesonormal(&wrong), plane) < 0.97);

    /* rounding: many identical normals give a zero covariance, not a negative one */
    mf_slope_moments acc = {0, 0, 0, 0, 0}, one = mf_moments_from_normal(mf_vec3_make(0.3, -0.7, 0.6));
    for (int k = 0; k < 1000; ++k)
        mf_moments_accumulate(&acc, &one, 1e-3);
    mf_gaussian_slopes gz = mf_moments_to_gaussian(&acc);
    CHECK(mf_gaussian_valid(&gz) && gz.var_x >= 0.0 && gz.var_x < 1e-14);
    /* not moments: E[x^2] < E[x]^2 by more than rounding */
    mf_slope_moments bad = {0.5, 0.0, 0.2, 0.0, 0.1};
    CHECK(isnan(mf_moments_to_gaussian(&bad).var_x));
    mf_slope_moments badc = {0.0, 0.0, 0.1, 0.2, 0.1}; /* |cov| > sqrt(var_x var_y) */
    CHECK(isnan(mf_moments_to_gaussian(&badc).cov_xy));
    CHECK(isnan(mf_moments_from_normal(mf_vec3_make(0.1, 0.2, -0.5)).mean_x));
}

static void test_base_roughness_n5(void)
{
    /* LEAN Eq. 6 / mf_moments_add_beckmann: a flat map plus base roughness is exactly Beckmann */
    mf_slope_moments flat = mf_moments_from_normal(mf_vec3_make(0, 0, 1));
    mf_slope_moments mb = mf_moments_add_beckmann(&flat, 0.3, 0.1);
    mf_gaussian_slopes g = mf_moments_to_gaussian(&mb);
    mf_ndf beck = mf_ndf_make(MF_NDF_BECKMANN, 0.3, 0.1);
    CHECK_REL(mf_gaussian_p22(&g, 0.2, -0.05), mf_ndf_p22(beck, 0.2, -0.05), 16 * DBL_EPSILON);
    /* Blinn-Phong exponent s: variance 1/s per axis (alpha = sqrt(2/s)) */
    double s = 256.0, a = mf_ndf_beckmann_alpha_from_blinn_phong(s);
    mf_slope_moments mbp = mf_moments_add_beckmann(&flat, a, a);
    CHECK_REL(mbp.m_xx, 1.0 / s, 2 * DBL_EPSILON);
    CHECK(isnan(mf_moments_add_beckmann(&flat, -0.1, 0.1).m_xx));

    /* correction C-N5(c): LEAN's Fig. 15/16 pack B / sc and M / sc^2 but add 1/s to the scaled M; after
     * unpacking (x sc^2) the base variance is sc^2 / s (16x for sc = 4).  Adding 1/(s sc^2) before
     * unscaling (or 1/s after) gives 1/s. */
    double sc = 4.0;
    mf_slope_moments m = mf_moments_from_normal(mf_vec3_normalize(mf_vec3_make(0.3, -0.2, 1.0)));
    mf_slope_moments packed = mf_moments_scale(&m, 1.0 / sc);
    mf_sym2 base = {1.0 / s, 0.0, 1.0 / s}, base_scaled = {1.0 / (s * sc * sc), 0.0, 1.0 / (s * sc * sc)};
    mf_slope_moments printed = mf_moments_add_covariance(&packed, base);
    mf_slope_moments printed_back = mf_moments_scale(&printed, sc);
    mf_gaussian_slopes gp = mf_moments_to_gaussian(&printed_back);
    CHECK_REL(gp.var_x, sc * sc / s, 1e-12);
    CHECK(fabs(gp.var_x * s - 1.0) > 1.0); /* the printed code's variance is wrong */
    mf_slope_moments fixed = mf_moments_add_covariance(&packed, base_scaled);
    mf_slope_moments fixed_back = mf_moments_scale(&fixed, sc);
    mf_gaussian_slopes gf = mf_moments_to_gaussian(&fixed_back);
    CHECK_REL(gf.var_x, 1.0 / s, 1e-12);
    CHECK_REL(gf.var_y, 1.0 / s, 1e-12);
    mf_slope_moments unscaled = mf_moments_scale(&packed, sc);
    mf_slope_moments after = mf_moments_add_covariance(&unscaled, base);
    CHECK_REL(mf_moments_to_gaussian(&after).var_x, 1.0 / s, 1e-12);
}

static void test_mixing(void)
{
    /* LEAN Eq. 7-9: mixing two layers t f + u g.  Reference: the moments of the normals of the
     * mixed height field sampled on the grid; ours: layer moments + cross moments. */
    const int n = 64;
    const double t = 0.3, u = 0.7;
    mf_slope_moments mf = {0, 0, 0, 0, 0}, mg = mf, mmix = mf;
    mf_slope_cross_moments cross = {0, 0, 0, 0};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            double x = (i + 0.5) / n, y = (j + 0.5) / n, w = 1.0 / (n * n);
            mf_vec3 nf = hf_normal(&field_a, x, y), ng = hf_normal(&field_b, x, y);
            mf_slope_moments a = mf_moments_from_normal(nf), b = mf_moments_from_normal(ng);
            mf_slope_cross_moments c = mf_moments_cross_from_normals(nf, ng);
            mf_moments_accumulate(&mf, &a, w);
            mf_moments_accumulate(&mg, &b, w);
            mf_moments_cross_accumulate(&cross, &c, w);
            /* the mixed field's slope is t grad f + u grad g */
            double fx, fy, gx, gy;
            hf_gradient(&field_a, x, y, &fx, &fy);
            hf_gradient(&field_b, x, y, &gx, &gy);
            mf_slope_moments mm = mf_moments_from_slope(t * fx + u * gx, t * fy + u * gy);
            mf_moments_accumulate(&mmix, &mm, w);
        }
    mf_slope_moments mixed_m = mf_moments_mix(&mf, &mg, &cross, t, u);
    CHECK_MOMENTS(mixed_m, mmix, 1e-14, 0.3);
    /* incoherent layers (different wave vectors): the mixing approximation is exact here too */
    mf_slope_cross_moments approx = mf_moments_cross_uncorrelated(&mf, &mg);
    mf_slope_moments mixed_a = mf_moments_mix(&mf, &mg, &approx, t, u);
    CHECK_MOMENTS(mixed_a, mmix, 1e-14, 0.3);
    /* coherent layers g = -f (LEAN Fig. 10): the equal mix is flat; the cross moments know it,
     * the approximation does not (it keeps half of each layer's variance) */
    mf_slope_moments fa = {0, 0, 0, 0, 0}, fb = fa;
    mf_slope_cross_moments cc = {0, 0, 0, 0};
    height_field sine = {1, {{0.02, 1, 0, 0}}, 0, 0};
    for (int i = 0; i < n; ++i) {
        mf_vec3 nf = hf_normal(&sine, (i + 0.5) / n, 0.0), ng = mf_vec3_make(-nf.x, -nf.y, nf.z);
        mf_slope_moments a = mf_moments_from_normal(nf), b = mf_moments_from_normal(ng);
        mf_slope_cross_moments c = mf_moments_cross_from_normals(nf, ng);
        mf_moments_accumulate(&fa, &a, 1.0 / n);
        mf_moments_accumulate(&fb, &b, 1.0 / n);
        mf_moments_cross_accumulate(&cc, &c, 1.0 / n);
    }
    mf_slope_moments flat = mf_moments_mix(&fa, &fb, &cc, 0.5, 0.5);
    mf_gaussian_slopes gflat = mf_moments_to_gaussian(&flat);
    CHECK_ABS(gflat.var_x, 0.0, 1e-17);
    mf_slope_cross_moments cu = mf_moments_cross_uncorrelated(&fa, &fb);
    mf_slope_moments aniso = mf_moments_mix(&fa, &fb, &cu, 0.5, 0.5);
    CHECK_REL(mf_moments_to_gaussian(&aniso).var_x, 0.5 * fa.m_xx, 1e-12);
}

static void test_leadr_transform(void)
{
    /* LEADR Eq. 12: texture-space moments of h(u, v) mapped to world moments of
     * H(x, y) = h(u(x, y), v(x, y)), (u, v) = (2x + y, y) (stretch + shear; integer entries keep H
     * periodic on the unit square).  Reference: H's normals sampled on a world grid. */
    const height_field tex = {2, {{0.01, 1, 2, 0.4}, {0.005, -3, 1, 1.3}}, 0.05, -0.02};
    height_field world = tex;
    for (int k = 0; k < tex.n; ++k) { /* k_world = L^T k with L = [[2, 1], [0, 1]] */
        world.w[k].kx = 2 * tex.w[k].kx;
        world.w[k].ky = tex.w[k].kx + tex.w[k].ky;
    }
    world.gx = 2 * tex.gx;
    world.gy = tex.gx + tex.gy;
    mf_slope_moments mt = hf_sampled(&tex, 64), mw = hf_sampled(&world, 64);
    mf_slope_moments tr = mf_moments_transform(&mt, 2.0, 0.0, 1.0, 1.0);
    CHECK_MOMENTS(tr, mw, 1e-14, 0.5);
    CHECK_MOMENTS(mw, hf_exact(&world), 1e-14, 0.5);
    /* covariance transforms as A Sigma A^T (Eq. 12 as printed), a rotation keeps the trace */
    mf_gaussian_slopes gt = mf_moments_to_gaussian(&mt), gw = mf_moments_to_gaussian(&tr);
    CHECK_ABS(gw.var_x, 4 * gt.var_x, 1e-15);
    CHECK_ABS(gw.cov_xy, 2 * gt.var_x + 2 * gt.cov_xy, 1e-15);
    double c = cos(0.7), s = sin(0.7);
    mf_slope_moments rot = mf_moments_transform(&mt, c, -s, s, c);
    mf_gaussian_slopes gr = mf_moments_to_gaussian(&rot);
    CHECK_REL(gr.var_x + gr.var_y, gt.var_x + gt.var_y, 1e-14);
    /* height scaling: moments of eta h */
    height_field scaled = tex;
    for (int k = 0; k < tex.n; ++k)
        scaled.w[k].a *= 2.5;
    scaled.gx *= 2.5;
    scaled.gy *= 2.5;
    mf_slope_moments ms = mf_moments_scale(&mt, 2.5);
    CHECK_MOMENTS(ms, hf_sampled(&scaled, 64), 1e-14, 0.5);
    CHECK(isnan(mf_moments_transform(&mt, NAN, 0, 0, 1).m_xx));
}

/* |A v - l v| for the decomposition */
static double eigen_residual(mf_sym2 a, const double v[2], double l)
{
    return hypot(a.xx * v[0] + a.xy * v[1] - l * v[0], a.xy * v[0] + a.yy * v[1] - l * v[1]);
}

static void test_eigen(mf_pcg32 *rng)
{
    /* random symmetric matrices over 12 decades: residual <= 8 eps (|l1| + |l2|), orthonormal,
     * ordered, and the matrix is rebuilt from l1 v1 v1^T + l2 v2 v2^T */
    for (int k = 0; k < 5000; ++k) {
        double sc = pow(10.0, -6.0 + 12.0 * mf_pcg32_next_double(rng));
        mf_sym2 a = {sc * (2 * mf_pcg32_next_double(rng) - 1), sc * (2 * mf_pcg32_next_double(rng) - 1),
                     sc * (2 * mf_pcg32_next_double(rng) - 1)};
        if (k % 4 == 0)
            a.xy = 0.0; /* diagonal (correction C-H6) */
        if (k % 8 == 1)
            a.yy = a.xx; /* equal diagonal */
        mf_eigen2 e = mf_sym2_eigen(a);
        double norm = fabs(e.l1) + fabs(e.l2);
        CHECK(e.l1 >= e.l2);
        CHECK(eigen_residual(a, e.v1, e.l1) <= 8 * DBL_EPSILON * norm);
        CHECK(eigen_residual(a, e.v2, e.l2) <= 8 * DBL_EPSILON * norm);
        CHECK_ABS(hypot(e.v1[0], e.v1[1]), 1.0, 4 * DBL_EPSILON);
        CHECK_ABS(e.v1[0] * e.v2[0] + e.v1[1] * e.v2[1], 0.0, 4 * DBL_EPSILON);
        double rxy = e.l1 * e.v1[0] * e.v1[1] + e.l2 * e.v2[0] * e.v2[1];
        CHECK_ABS(rxy, a.xy, 8 * DBL_EPSILON * norm);
    }
    /* correction C-H6: diagonal covariance, b = 0.  Hery's code takes v = (1, (l - a)/b): 0/0 and x/0. */
    mf_sym2 d = {0.04, 0.0, 0.01};
    double del = sqrt(d.xx * d.xx + 4 * d.xy * d.xy - 2 * d.xx * d.yy + d.yy * d.yy);
    double l1 = 0.5 * (d.xx + d.yy + del), l2 = 0.5 * (d.xx + d.yy - del);
    CHECK(!isfinite((l1 - d.xx) / d.xy) && !isfinite((l2 - d.xx) / d.xy)); /* the printed solver fails */
    mf_eigen2 e = mf_sym2_eigen(d);
    CHECK(e.l1 == 0.04 && e.l2 == 0.01 && e.v1[0] == 1.0 && e.v1[1] == 0.0 && e.v2[0] == 0.0 && e.v2[1] == 1.0);
    mf_sym2 dy = {0.01, 0.0, 0.04};
    e = mf_sym2_eigen(dy);
    CHECK(e.l1 == 0.04 && e.l2 == 0.01 && fabs(e.v1[1]) == 1.0 && e.v1[0] == 0.0);
    /* isotropic: any orthonormal pair; mfkit returns the axes */
    mf_sym2 iso = {0.02, 0.0, 0.02};
    e = mf_sym2_eigen(iso);
    CHECK(e.l1 == 0.02 && e.l2 == 0.02 && e.v1[0] == 1.0 && e.v2[1] == 1.0);
    /* nearly isotropic and tiny off-diagonal: finite unit vectors, eigenvalues 1 -+ 1e-300 */
    mf_sym2 near = {1.0, 1e-300, 1.0};
    e = mf_sym2_eigen(near);
    CHECK(isfinite(e.v1[0]) && isfinite(e.v1[1]));
    CHECK_ABS(hypot(e.v1[0], e.v1[1]), 1.0, 4 * DBL_EPSILON);
    CHECK_REL(e.v1[0], sqrt(0.5), 4 * DBL_EPSILON);
    /* ill-conditioned PSD: l2 = det / l1 keeps its relative accuracy (m - r would give 0) */
    mf_sym2 thin = {1.0, 0.5e-10, 1e-20};
    e = mf_sym2_eigen(thin);
    CHECK_REL(e.l2, 7.5e-21, 1e-14);
    /* correlated: [[0.05, 0.02], [0.02, 0.03]]: l = 0.04 +- sqrt(0.0005) */
    mf_sym2 corr = {0.05, 0.02, 0.03};
    e = mf_sym2_eigen(corr);
    CHECK_REL(e.l1, 0.04 + sqrt(0.0005), 4 * DBL_EPSILON);
    CHECK_REL(e.l2, 0.04 - sqrt(0.0005), 16 * DBL_EPSILON);
    mf_sym2 nanm = {NAN, 0, 1};
    CHECK(isnan(mf_sym2_eigen(nanm).l1));
    /* roughness of a covariance: alpha_k = sqrt(2 l_k), NaN if not PSD */
    mf_aniso_roughness r = mf_roughness_from_covariance(corr);
    CHECK_REL(r.alpha1, sqrt(2 * (0.04 + sqrt(0.0005))), 4 * DBL_EPSILON);
    mf_sym2 indef = {0.01, 0.02, 0.01};
    CHECK(isnan(mf_roughness_from_covariance(indef).alpha1));
}

static void test_hery(void)
{
    /* correction C-H1: displacement w(u, v) on R(u, v) = (2.5 u, 0.6 v, 0).  Reference: the normals of
     * the displaced surface P = R + w z from the cross product P_u x P_v = (-0.6 w_u, -2.5 w_v, 1.5),
     * sampled over one period; their world-slope covariance is var(w_u)/2.5^2, ... (slope per arc
     * length).  The printed s_u = w_u |R_u|^(1/2) gives var(w_u) * 2.5 instead. */
    const height_field w = {2, {{0.02, 1, 2, 0.4}, {0.01, -3, 1, 1.3}}, 0.0, 0.0};
    const double lu = 2.5, lv = 0.6;
    const int n = 64;
    mf_slope_moments dw = {0, 0, 0, 0, 0}, world = dw;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            double wu, wv;
            hf_gradient(&w, (i + 0.5) / n, (j + 0.5) / n, &wu, &wv);
            mf_slope_moments m = mf_moments_from_slope(wu, wv);
            mf_moments_accumulate(&dw, &m, 1.0 / (n * n));
            mf_vec3 pu = {lu, 0, wu}, pv = {0, lv, wv};
            mf_slope_moments mw = mf_moments_from_normal(mf_vec3_cross(pu, pv));
            mf_moments_accumulate(&world, &mw, 1.0 / (n * n));
        }
    mf_gaussian_slopes gw = mf_moments_to_gaussian(&world);
    mf_sym2 s = mf_hery_slope_covariance(&dw, lu, lv);
    CHECK_REL(s.xx, gw.var_x, 1e-13);
    CHECK_REL(s.yy, gw.var_y, 1e-13);
    CHECK_REL(s.xy, gw.cov_xy, 1e-13);
    mf_gaussian_slopes gdw = mf_moments_to_gaussian(&dw);
    double printed_xx = gdw.var_x * lu; /* (w_u |R_u|^(1/2))^2 */
    CHECK(fabs(printed_xx / gw.var_x - 1.0) > 1.0);
    CHECK(isnan(mf_hery_slope_covariance(&dw, 0.0, lv).xx));

    /* correction C-H2: isotropic displacement, variance 0.02 per axis, m_orig = 0.2: Eq. 3/8 give
     * m_eff = sqrt(m^2 + 2 sigma^2) = 0.28284; the printed Eq. 10 factor 1/2 gives 0.22361. */
    mf_sym2 iso = {0.02, 0.0, 0.02};
    mf_aniso_roughness r = mf_hery_bump_roughness(0.2, 0.2, iso);
    CHECK_REL(r.alpha1, sqrt(0.08), 4 * DBL_EPSILON);
    CHECK_REL(r.alpha2, sqrt(0.08), 4 * DBL_EPSILON);
    CHECK_ABS(r.alpha1, 0.28284, 1e-5);
    double printed = sqrt(0.04 + 0.5 * 0.02);
    CHECK_ABS(printed, 0.22361, 1e-5);
    CHECK(fabs(printed - r.alpha1) > 0.05);

    /* correction C-H5: anisotropic base (0.3, 0.1) with displacement eigenvectors at 30 degrees.  The
     * general form decomposes diag(m^2) + 2 Sigma; Eq. 12 (m_orig,k^2 + l_k of 2 Sigma alone) is
     * only right when they are aligned.  Check: the anisotropic Beckmann returned is the Gaussian of
     * covariance diag(m^2/2) + Sigma (the exact convolution), rebuilt from alphas and directions. */
    double c = cos(MF_PI / 6), sn = sin(MF_PI / 6), la = 0.03, lb = 0.005;
    mf_sym2 rot = {la * c * c + lb * sn * sn, (la - lb) * c * sn, la * sn * sn + lb * c * c};
    mf_aniso_roughness g = mf_hery_bump_roughness(0.3, 0.1, rot);
    double cov_xx = 0.5 * (g.alpha1 * g.alpha1 * g.dir1[0] * g.dir1[0] + g.alpha2 * g.alpha2 * g.dir2[0] * g.dir2[0]);
    double cov_xy = 0.5 * (g.alpha1 * g.alpha1 * g.dir1[0] * g.dir1[1] + g.alpha2 * g.alpha2 * g.dir2[0] * g.dir2[1]);
    double cov_yy = 0.5 * (g.alpha1 * g.alpha1 * g.dir1[1] * g.dir1[1] + g.alpha2 * g.alpha2 * g.dir2[1] * g.dir2[1]);
    CHECK_REL(cov_xx, 0.045 + rot.xx, 16 * DBL_EPSILON);
    CHECK_REL(cov_xy, rot.xy, 16 * DBL_EPSILON);
    CHECK_REL(cov_yy, 0.005 + rot.yy, 16 * DBL_EPSILON);
    mf_sym2 two_sigma = {2 * rot.xx, 2 * rot.xy, 2 * rot.yy};
    mf_eigen2 ed = mf_sym2_eigen(two_sigma);
    double eq12_1 = sqrt(0.09 + ed.l1), eq12_2 = sqrt(0.01 + ed.l2);
    CHECK(fabs(eq12_1 - g.alpha1) > 1e-3 || fabs(eq12_2 - g.alpha2) > 1e-3);
    mf_sym2 aligned = {la, 0.0, lb}; /* aligned with the base: Eq. 12 and the general form agree */
    mf_aniso_roughness ga = mf_hery_bump_roughness(0.3, 0.1, aligned);
    CHECK_REL(ga.alpha1, sqrt(0.09 + 2 * la), 4 * DBL_EPSILON);
    CHECK_REL(ga.alpha2, sqrt(0.01 + 2 * lb), 4 * DBL_EPSILON);
    CHECK(isnan(mf_hery_bump_roughness(-0.1, 0.1, aligned).alpha1));
}

static void test_toksvig(void)
{
    /* definitions [Toksvig 2005]: len = 1/(1 + sigma^2); 1/(ft s) = 1/s + sigma^2 */
    CHECK(mf_toksvig_variance(1.0) == 0.0 && mf_toksvig_factor(1.0, 100.0) == 1.0);
    for (double var = 1e-6; var < 10.0; var *= 3.7) {
        double len = 1.0 / (1.0 + var);
        CHECK_REL(mf_toksvig_variance(len), var, 1e-15 / var + 4 * DBL_EPSILON);
        double s = 64.0, ft = mf_toksvig_factor(len, s);
        CHECK_REL(1.0 / (ft * s), 1.0 / s + mf_toksvig_variance(len), 8 * DBL_EPSILON);
        double a = mf_ndf_beckmann_alpha_from_blinn_phong(s);
        CHECK_REL(mf_toksvig_beckmann_alpha(len, a), mf_ndf_beckmann_alpha_from_blinn_phong(ft * s), 8 * DBL_EPSILON);
    }
    /* small slopes: Toksvig's sigma^2 is the per-axis slope variance v of an isotropic field, up to
     * O(v): 1 - len = E|s|^2/2 - O(E|s|^4).  Isotropic field: equal waves along x and y, v = 1e-4. */
    const double amp = sqrt(2e-4) / (2 * MF_PI);
    const height_field iso = {2, {{amp, 1, 0, 0.2}, {amp, 0, 1, 1.0}}, 0, 0};
    const int n = 64;
    mf_vec3 sum = {0, 0, 0};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            sum = mf_vec3_add(sum, mf_vec3_scale(hf_normal(&iso, (i + 0.5) / n, (j + 0.5) / n), 1.0 / (n * n)));
    mf_slope_moments m = hf_sampled(&iso, n);
    double v = mf_moments_to_gaussian(&m).var_x;
    CHECK_REL(v, 1e-4, 1e-12);
    double tv = mf_toksvig_variance(mf_vec3_length(sum));
    CHECK_REL(tv, v, 5 * v);
    /* domain */
    CHECK(isnan(mf_toksvig_variance(0.0)) && isnan(mf_toksvig_variance(1.0000001)) && isnan(mf_toksvig_variance(NAN)));
    CHECK(isnan(mf_toksvig_factor(0.5, 0.0)) && isnan(mf_toksvig_beckmann_alpha(0.5, -1.0)));
}

int main(void)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20100219), 7);
    test_lean_moments();
    test_base_roughness_n5();
    test_mixing();
    test_leadr_transform();
    test_eigen(&rng);
    test_hery();
    test_toksvig();
    MF_TEST_MAIN_END();
}
