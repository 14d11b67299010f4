/*
 * Folder counts the write tests share (test_writer, test_writer_faults,
 * test_io, test_faults): what a failed write must leave behind is checked
 * by counting entries before and after.
 */
#ifndef FDT_TESTDIR_H
#define FDT_TESTDIR_H

#include <dirent.h>
#include <string.h>

/* Entries of dir other than . and .. (-1 if it cannot be read). */
static inline int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return n;
}

/* Entries of dir whose name holds ".tmp." (the writer's temporaries; -1
 * if it cannot be read). */
static inline int count_temps(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        n += strstr(e->d_name, ".tmp.") != NULL;
    closedir(d);
    return n;
}

#endif
