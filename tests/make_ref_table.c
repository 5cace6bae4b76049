/*
 * make_ref_table.c -- writes the reference LTC table's CSV (tests/data/reference, read with
 * mf_ltc_reference_read_csv) as an mfkit table file, for the front-end test (test_frontend.sh):
 * the pure C build has no fitter, and CSV is a write-only table format.
 *   usage: make_ref_table IN.csv OUT   (OUT's extension picks the format: .json, .npy, .dds)
 * Exit 0 on success, 1 with a one-line message on stderr otherwise.
 */
#include <mfkit/io/mf_ltc_reference.h>
#include <mfkit/io/mf_table_io.h>

#include <stdio.h>

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: make_ref_table IN.csv OUT\n");
        return 1;
    }
    mf_table t;
    char msg[1024];
    mf_status st = mf_ltc_reference_read_csv(argv[1], &t, msg, sizeof msg);
    if (st != MF_OK) {
        fprintf(stderr, "make_ref_table: %s\n", msg[0] ? msg : mf_status_str(st));
        return 1;
    }
    st = mf_table_write(argv[2], &t, NULL, NULL, msg, sizeof msg);
    mf_table_free(&t);
    if (st != MF_OK) {
        fprintf(stderr, "make_ref_table: %s\n", msg[0] ? msg : mf_status_str(st));
        return 1;
    }
    return 0;
}
