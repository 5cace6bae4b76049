/* mf_ltc_table.c -- the isotropic LTC table layout (see mf_ltc_table.h). */
#include "mfkit/mf_ltc_table.h"

#include <stdio.h>
#include <string.h>

const char *const mf_ltc_table_fields[MF_LTC_NFIELDS] = {"minv_00", "minv_20", "minv_02", "minv_22",
                                                         "magnitude", "fresnel", "zero", "sphere"};

mf_status mf_ltc_table_create(mf_table *t, int n_r, int n_u)
{
    return mf_ltc_table_create_range(t, n_r, 0.0, 1.0, n_u, 0.0, 1.0);
}

static int range_ok(double lo, double hi) { return lo >= 0.0 && hi <= 1.0 && lo < hi; }

mf_status mf_ltc_table_create_range(mf_table *t, int n_r, double r_lo, double r_hi, int n_u, double u_lo,
                                    double u_hi)
{
    if (n_r < 2 || n_u < 2 || !range_ok(r_lo, r_hi) || !range_ok(u_lo, u_hi)) {
        memset(t, 0, sizeof *t);
        return MF_ERR_DOMAIN;
    }
    mf_table_axis axes[2];
    memset(axes, 0, sizeof axes);
    snprintf(axes[0].name, sizeof axes[0].name, "r");
    snprintf(axes[0].physical, sizeof axes[0].physical, "alpha");
    axes[0].size = n_r;
    axes[0].lo = r_lo;
    axes[0].hi = r_hi;
    axes[0].mapping = MF_AXIS_SQUARE;
    axes[0].physical_min = MF_LTC_ALPHA_MIN;
    snprintf(axes[1].name, sizeof axes[1].name, "u");
    snprintf(axes[1].physical, sizeof axes[1].physical, "cos_theta_o");
    axes[1].size = n_u;
    axes[1].lo = u_lo;
    axes[1].hi = u_hi;
    axes[1].mapping = MF_AXIS_ONE_MINUS_SQUARE;
    axes[1].physical_min = cos(MF_LTC_THETA_MAX);
    mf_status st = mf_table_create(t, 2, axes, MF_LTC_NFIELDS, mf_ltc_table_fields);
    if (st == MF_OK)
        st = mf_table_set_meta(t, "layout", "mfkit-ltc-isotropic-1");
    if (st != MF_OK)
        mf_table_free(t);
    return st;
}

double mf_ltc_table_alpha(const mf_table *t, int ir)
{
    return mf_table_axis_physical(&t->axes[0], mf_table_axis_param(&t->axes[0], ir));
}

double mf_ltc_table_cos_theta(const mf_table *t, int iu)
{
    return mf_table_axis_physical(&t->axes[1], mf_table_axis_param(&t->axes[1], iu));
}

mf_status mf_ltc_table_pack(double a, double b, double c, double d, double out4[4])
{
    mf_mat3 inv;
    mf_status st = mf_mat3_inverse(mf_ltc_matrix_isotropic(a, b, c, d), &inv);
    if (st != MF_OK)
        return st;
    double s = inv.m[1][1];
    if (!isfinite(s) || s == 0.0)
        return MF_ERR_DOMAIN;
    out4[0] = inv.m[0][0] / s;
    out4[1] = inv.m[2][0] / s;
    out4[2] = inv.m[0][2] / s;
    out4[3] = inv.m[2][2] / s;
    return MF_OK;
}

mf_status mf_ltc_table_unpack(const double in4[4], mf_ltc *ltc)
{
    mf_mat3 inv = {{{in4[0], 0.0, in4[2]}, {0.0, 1.0, 0.0}, {in4[1], 0.0, in4[3]}}};
    mf_mat3 m;
    mf_status st = mf_mat3_inverse(inv, &m);
    if (st != MF_OK)
        return st;
    return mf_ltc_init(ltc, m);
}
