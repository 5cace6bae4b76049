/*
 * test_files.h -- file helpers shared by mfkit's C tests that write files (tests/ only): whole-file
 * reads and writes, sizes, leftover temporaries, tools on the PATH, and removing a scratch
 * directory made with mkdtemp.  POSIX: define _POSIX_C_SOURCE 200809L before any include.
 */
#ifndef MF_TEST_FILES_H
#define MF_TEST_FILES_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Size of the file at path in bytes, -1 if it does not exist. */
static inline long mf_test_file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static inline int mf_test_file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* The whole file (malloc'd, *len bytes plus a terminating NUL), NULL if it cannot be read. */
static inline unsigned char *mf_test_read_file(const char *path, long *len)
{
    *len = mf_test_file_size(path);
    FILE *f = fopen(path, "rb");
    if (!f || *len < 0) {
        if (f)
            fclose(f);
        return NULL;
    }
    unsigned char *p = malloc((size_t)*len + 1);
    if (p && fread(p, 1, (size_t)*len, f) != (size_t)*len) {
        free(p);
        p = NULL;
    }
    fclose(f);
    if (p)
        p[*len] = 0;
    return p;
}

/* Writes len bytes to path (replacing it); 0 on success, -1 on any error. */
static inline int mf_test_write_file(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    int ok = fwrite(data, 1, len, f) == len;
    return (fclose(f) == 0 && ok) ? 0 : -1;
}

/* Number of entries of dir whose name contains ".tmp" (temporaries an atomic writer left), -1 if
 * dir cannot be read. */
static inline int mf_test_count_temporaries(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp") != NULL)
            ++n;
    closedir(d);
    return n;
}

/* 1 if the shell finds the program name on the PATH. */
static inline int mf_test_have_tool(const char *name)
{
    char cmd[256];
    snprintf(cmd, sizeof cmd, "command -v %s >/dev/null 2>&1", name);
    return system(cmd) == 0;
}

/* Removes the files of the (flat) directory dir, keeping dir; 0 on success, -1 if dir cannot be
 * read. */
static inline int mf_test_clear_dir(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    struct dirent *e;
    char path[1024];
    while ((e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        remove(path);
    }
    closedir(d);
    return 0;
}

/* Removes the files of the (flat) directory dir, then dir; 0 on success. */
static inline int mf_test_remove_dir(const char *dir) { return mf_test_clear_dir(dir) == 0 ? rmdir(dir) : -1; }

#endif /* MF_TEST_FILES_H */
