/* mf_sample.c -- direction samplers and their pdfs (see mf_sample.h). */
#include "mfkit/mf_sample.h"
#include "mfkit/mf_smith.h"

mf_vec3 mf_sample_uniform_sphere(const double u[2])
{
    double z = 1.0 - 2.0 * u[0];
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * MF_PI * u[1];
    return mf_vec3_make(r * cos(phi), r * sin(phi), z);
}

double mf_pdf_uniform_sphere(void) { return 0.25 * MF_INV_PI; }

mf_vec3 mf_sample_uniform_hemisphere(const double u[2])
{
    double z = u[0];
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * MF_PI * u[1];
    return mf_vec3_make(r * cos(phi), r * sin(phi), z);
}

double mf_pdf_uniform_hemisphere(mf_vec3 w) { return w.z >= 0.0 ? 0.5 * MF_INV_PI : 0.0; }

/* Concentric map of [0,1)^2 to the unit disk [Shirley & Chiu 1997]. */
static void concentric_disk(const double u[2], double *x, double *y)
{
    double a = 2.0 * u[0] - 1.0, b = 2.0 * u[1] - 1.0;
    if (a == 0.0 && b == 0.0) {
        *x = *y = 0.0;
        return;
    }
    double r, phi;
    if (fabs(a) > fabs(b)) {
        r = a;
        phi = 0.25 * MF_PI * (b / a);
    } else {
        r = b;
        phi = 0.5 * MF_PI - 0.25 * MF_PI * (a / b);
    }
    *x = r * cos(phi);
    *y = r * sin(phi);
}

mf_vec3 mf_sample_cosine_hemisphere(const double u[2])
{
    double x, y;
    concentric_disk(u, &x, &y);
    return mf_vec3_make(x, y, sqrt(fmax(0.0, 1.0 - x * x - y * y)));
}

mf_vec3 mf_sample_cosine_hemisphere_polar(const double u[2])
{
    double r = sqrt(u[0]), phi = 2.0 * MF_PI * u[1];
    return mf_vec3_make(r * cos(phi), r * sin(phi), sqrt(1.0 - u[0]));
}

double mf_pdf_cosine_hemisphere(mf_vec3 w) { return w.z > 0.0 ? w.z * MF_INV_PI : 0.0; }

mf_vec3 mf_sample_ndf_normal(mf_ndf ndf, const double u[2])
{
    if (!mf_ndf_valid(ndf))
        return mf_vec3_make(NAN, NAN, NAN);
    /* Radius of the slope in the stretched (alpha = 1) space: invert the radial CDF
     * Beckmann 1 - exp(-r^2), GGX 1 - 1/(1 + r^2) (slope forms of [Walter 2007, Eq. 28, 35]). */
    double r = (ndf.type == MF_NDF_BECKMANN) ? sqrt(-log1p(-u[0])) : sqrt(u[0] / (1.0 - u[0]));
    double phi = 2.0 * MF_PI * u[1];
    double sx = ndf.alpha_x * r * cos(phi), sy = ndf.alpha_y * r * sin(phi);
    return mf_normal_from_slope(sx, sy);
}

double mf_pdf_ndf_normal(mf_ndf ndf, mf_vec3 wm)
{
    return wm.z > 0.0 ? mf_ndf_d(ndf, wm) * wm.z : 0.0;
}

mf_vec3 mf_sample_ggx_vndf(double alpha_x, double alpha_y, mf_vec3 wo, const double u[2])
{
    if (!(alpha_x > 0.0) || !(alpha_y > 0.0) || !(wo.z > 0.0) || !mf_vec3_isfinite(wo))
        return mf_vec3_make(NAN, NAN, NAN);
    /* [Heitz 2018, Listing 1] */
    mf_vec3 vh = mf_vec3_normalize(mf_vec3_make(alpha_x * wo.x, alpha_y * wo.y, wo.z));
    double lensq = vh.x * vh.x + vh.y * vh.y;
    mf_vec3 t1 = lensq > 0.0 ? mf_vec3_scale(mf_vec3_make(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq))
                             : mf_vec3_make(1.0, 0.0, 0.0);
    mf_vec3 t2 = mf_vec3_cross(vh, t1);
    double r = sqrt(u[0]);
    double phi = 2.0 * MF_PI * u[1];
    double p1 = r * cos(phi), p2 = r * sin(phi);
    double s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(fmax(0.0, 1.0 - p1 * p1)) + s * p2;
    double pz = sqrt(fmax(0.0, 1.0 - p1 * p1 - p2 * p2));
    mf_vec3 nh = mf_vec3_add(mf_vec3_add(mf_vec3_scale(t1, p1), mf_vec3_scale(t2, p2)), mf_vec3_scale(vh, pz));
    return mf_vec3_normalize(mf_vec3_make(alpha_x * nh.x, alpha_y * nh.y, fmax(0.0, nh.z)));
}

double mf_pdf_ggx_vndf(double alpha_x, double alpha_y, mf_vec3 wo, mf_vec3 wm)
{
    if (!(wo.z > 0.0))
        return NAN;
    double cos_om = mf_vec3_dot(wo, wm);
    if (cos_om <= 0.0 || wm.z <= 0.0)
        return 0.0;
    mf_ndf ndf = mf_ndf_make(MF_NDF_GGX, alpha_x, alpha_y);
    return mf_smith_g1(ndf, wo) * cos_om * mf_ndf_d(ndf, wm) / wo.z;
}

double mf_pdf_reflected(double pdf_wm, mf_vec3 wo, mf_vec3 wm)
{
    return pdf_wm / (4.0 * fabs(mf_vec3_dot(wo, wm)));
}
