/* A program outside the mfkit tree that uses the installed library. */
#include <mfkit/io/mf_table_io.h>
#include <mfkit/mfkit.h>
#include <stdio.h>
#include <stdlib.h>

int main(void)
{
    mf_ndf ndf = mf_ndf_make(MF_NDF_GGX, 0.5, 0.5);
    double d = mf_ndf_d(ndf, mf_vec3_make(0.0, 0.0, 1.0));
    double expect = 1.0 / (MF_PI * 0.25);
    if (!(fabs(d - expect) <= 1e-15 * expect)) {
        fprintf(stderr, "consumer: D = %.17g, expected %.17g\n", d, expect);
        return 1;
    }
    /* table I/O (mfkit::io): a 2-texel table to JSON and back, bitwise */
    mf_table_axis ax = {0};
    snprintf(ax.name, sizeof ax.name, "u");
    snprintf(ax.physical, sizeof ax.physical, "x");
    ax.size = 2;
    ax.hi = 1.0;
    ax.physical_min = -INFINITY;
    const char *field = "v";
    mf_table t, r;
    char path[64], msg[512];
    snprintf(path, sizeof path, "consumer_table_%d.json", rand() % 1000);
    if (mf_table_create(&t, 1, &ax, 1, &field) != MF_OK)
        return 1;
    t.data[0] = 0.25;
    t.data[1] = -3.5;
    if (mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) != MF_OK ||
        mf_table_read(path, &r, NULL, msg, sizeof msg) != MF_OK) {
        fprintf(stderr, "consumer: %s\n", msg);
        return 1;
    }
    remove(path);
    int same = r.data[0] == 0.25 && r.data[1] == -3.5;
    mf_table_free(&t);
    mf_table_free(&r);
    if (!same) {
        fprintf(stderr, "consumer: the JSON table did not read back\n");
        return 1;
    }
    printf("consumer: ok (%s)\n", mf_status_str(MF_OK));
    return 0;
}
