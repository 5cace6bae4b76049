/*
 * test_tables.h -- helpers shared by mfkit's C tests of tables and their gates (tests/ only):
 * bitwise comparison of two tables' metadata, a float's bits, and finding and printing the
 * records of a check run.
 */
#ifndef MF_TEST_TABLES_H
#define MF_TEST_TABLES_H

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <mfkit/mf_check.h>
#include <mfkit/mf_table.h>

/* 1 if a and b have the same axes, fields and metadata, the doubles compared bit for bit. */
static inline int mf_test_same_metadata(const mf_table *a, const mf_table *b)
{
    if (a->naxes != b->naxes || a->nfields != b->nfields || a->nmeta != b->nmeta)
        return 0;
    for (int k = 0; k < a->naxes; ++k) {
        const mf_table_axis *x = &a->axes[k], *y = &b->axes[k];
        if (strcmp(x->name, y->name) || strcmp(x->physical, y->physical) || x->size != y->size ||
            memcmp(&x->lo, &y->lo, sizeof(double)) || memcmp(&x->hi, &y->hi, sizeof(double)) ||
            x->mapping != y->mapping || memcmp(&x->physical_min, &y->physical_min, sizeof(double)))
            return 0;
    }
    for (int f = 0; f < a->nfields; ++f)
        if (strcmp(a->fields[f], b->fields[f]))
            return 0;
    for (int i = 0; i < a->nmeta; ++i)
        if (strcmp(a->meta[i].key, b->meta[i].key) || strcmp(a->meta[i].value, b->meta[i].value))
            return 0;
    return 1;
}

static inline uint32_t mf_test_float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

/* The record named name among the n records c, NULL if there is none. */
static inline const mf_check *mf_test_find_check(const mf_check *c, int n, const char *name)
{
    for (int i = 0; i < n; ++i)
        if (!strcmp(c[i].name, name))
            return &c[i];
    return NULL;
}

/* 1 if the record named name among the n records c passed, 0 if it failed, -1 if there is none. */
static inline int mf_test_check_passed(const mf_check *c, int n, const char *name)
{
    const mf_check *x = mf_test_find_check(c, n, name);
    return x ? (x->passed != 0) : -1;
}

/* Prints the n records c under a title, one line each. */
static inline void mf_test_print_checks(const char *title, const mf_check *c, int n)
{
    printf("-- %s\n", title);
    for (int i = 0; i < n; ++i)
        printf("  %-20s %-5s worst %-11.4g bound %-9.3g cases %-6ld %s\n", c[i].name, c[i].passed ? "pass" : "FAIL",
               c[i].worst, c[i].bound, c[i].cases, c[i].worst_at);
}

#endif /* MF_TEST_TABLES_H */
