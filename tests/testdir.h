/*
 * Folder counts the write tests share (test_writer, test_writer_faults,
 * test_writer_stream, test_io, test_faults): what a failed write must
 * leave behind is checked by counting entries before and after.
 */
#ifndef FDT_TESTDIR_H
#define FDT_TESTDIR_H

#include <dirent.h>
#include <string.h>

/* Entries of dir other than . and .. whose name holds part (NULL: every
 * one); -1 if dir cannot be read. */
static inline int count_named(const char *dir, const char *part)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0 &&
             (!part || strstr(e->d_name, part) != NULL);
    closedir(d);
    return n;
}

/* Entries of dir other than . and .. (-1 if it cannot be read). */
static inline int count_entries(const char *dir)
{
    return count_named(dir, NULL);
}

/* Entries of dir whose name holds ".tmp." (the writer's temporaries; -1
 * if it cannot be read). */
static inline int count_temps(const char *dir)
{
    return count_named(dir, ".tmp.");
}

#endif
