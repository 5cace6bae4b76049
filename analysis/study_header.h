/*
 * study_header.h -- the provenance line every analysis CSV starts with (analysis/ only):
 *   # command=<name> <args...>, mfkit=<version>, seed=<seed>, date=<UTC ISO 8601>
 * analysis/plot.py parses this line and prints it under each figure.
 */
#ifndef MF_STUDY_HEADER_H
#define MF_STUDY_HEADER_H

#include <stdio.h>
#include <time.h>

#ifndef MFKIT_VERSION
#define MFKIT_VERSION "unknown"
#endif

/* name replaces argv[0] (a build path) so the line names the program, not where it was built. */
static inline void study_write_header(FILE *f, const char *name, int argc, char **argv, const char *seed)
{
    char date[32];
    time_t now = time(NULL);
    strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", gmtime(&now));
    fprintf(f, "# command=%s", name);
    for (int i = 1; i < argc; ++i)
        fprintf(f, " %s", argv[i]);
    fprintf(f, ", mfkit=%s, seed=%s, date=%s\n", MFKIT_VERSION, seed, date);
}

#endif /* MF_STUDY_HEADER_H */
