/* A program outside the mfkit tree that uses the installed fitter (mfkit::fit, mfkit-fit.pc):
 * it fits a 4 x 4 GGX LTC table, checks it and writes it as JSON, which must read back bitwise
 * (table files store float32: docs/tables.md, so the float64 fit comes back rounded to float). */
#include <mfkit/fit/mf_ltcfit.h>
#include <mfkit/io/mf_table_io.h>
#include <mfkit/mfkit.h>

#include <math.h>
#include <stdio.h>
#include <unistd.h>

int main(void)
{
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    if (!ggx) {
        fprintf(stderr, "consumer_fit: no model 'ggx' in the registry\n");
        return 1;
    }
    mf_ltcfit_options o;
    mf_ltcfit_options_default(&o);
    o.n_r = o.n_u = 4;
    o.samples = 256;
    mf_table t, r;
    mf_ltcfit_result res;
    char msg[1024], path[64];
    mf_status st = mf_ltcfit_table(ggx, &o, &t, &res, msg, sizeof msg);
    if (st != MF_OK) {
        fprintf(stderr, "consumer_fit: fit: %s (%s)\n", msg, mf_status_str(st));
        return 1;
    }
    /* Every stored value finite, and the magnitude (the albedo) in (0, 1]: GGX with F = 1 loses
     * energy to masking but never gains it. */
    size_t n = (size_t)4 * 4;
    for (size_t i = 0; i < n * (size_t)t.nfields; ++i)
        if (!isfinite(t.data[i])) {
            fprintf(stderr, "consumer_fit: value %zu is %g\n", i, t.data[i]);
            return 1;
        }
    for (size_t i = 0; i < n; ++i) {
        double m = t.data[i * (size_t)t.nfields + MF_LTC_F_MAGNITUDE];
        if (!(m > 0.0 && m <= 1.0)) {
            fprintf(stderr, "consumer_fit: texel %zu: magnitude %.17g outside (0, 1]\n", i, m);
            return 1;
        }
    }
    snprintf(path, sizeof path, "consumer_ltc_%ld.json", (long)getpid());
    if (mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) != MF_OK ||
        mf_table_read(path, &r, NULL, msg, sizeof msg) != MF_OK) {
        fprintf(stderr, "consumer_fit: %s\n", msg);
        return 1;
    }
    remove(path);
    int same = r.nfields == t.nfields;
    for (size_t i = 0; same && i < n * (size_t)t.nfields; ++i)
        same = r.data[i] == (double)(float)t.data[i];
    printf("consumer_fit: %d x %d GGX LTC table, worst residual %.3g, JSON round trip %s\n", o.n_r, o.n_u,
           res.worst_residual, same ? "bitwise" : "DIFFERS");
    mf_table_free(&t);
    mf_table_free(&r);
    mf_ltcfit_result_free(&res);
    return same ? 0 : 1;
}
