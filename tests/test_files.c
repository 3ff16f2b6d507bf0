/* SPDX-License-Identifier: MIT */
/* test_files.c: the atomic writer never replaces what is not a file, cleans up after
   killed processes, takes any legal name, and commits groups of outputs together. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "btdf_test.h"
#include "btdf_io.h"
#include "io/tmpfile.h"

static char dir[256];

static int setup(void **state)
{
    (void)state;
    return btdf_test_mkdtemp(dir, sizeof dir, "files");
}

static int teardown(void **state)
{
    (void)state;
    return btdf_test_rmtree(dir);
}

static void at(char *out, size_t len, const char *name)
{
    snprintf(out, len, "%s/%s", dir, name);
}

static char *slurp(const char *path)
{
    static char buf[256];
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    return buf;
}

static btdf_status put(const char *path, const char *text)
{
    btdf_bytes b = {text, strlen(text)};
    char msg[256];
    return btdf_write_file_atomic(path, ".txt", btdf_write_bytes, &b, msg, sizeof msg);
}

static btdf_status failing_writer(void *ctx, const char *tmp, char *msg, size_t msglen)
{
    (void)ctx;
    FILE *f = fopen(tmp, "wb");
    if (f) {
        fputs("half", f);
        fclose(f);
    }
    snprintf(msg, msglen, "disk full (simulated)");
    return BTDF_EIO;
}

/* Entries in dir other than . and .. */
static int entries(void)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return n;
}

/* A file made directly, not through the writer. */
static void raw(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

static void never_replaces_a_non_file(void **state)
{
    (void)state;
    char fifo[512], sub[512], link_[512], target[512];
    at(fifo, sizeof fifo, "pipe.json");
    at(sub, sizeof sub, "folder.csv");
    at(link_, sizeof link_, "link.csv");
    at(target, sizeof target, "target.csv");
    assert_int_equal(mkfifo(fifo, 0600), 0);
    assert_int_equal(mkdir(sub, 0700), 0);
    assert_status(BTDF_OK, put(target, "kept"));
    assert_int_equal(symlink(target, link_), 0);
    assert_status(BTDF_EINVAL, put(fifo, "x"));
    assert_status(BTDF_EINVAL, put(sub, "x"));
    assert_status(BTDF_EINVAL, put(link_, "x"));
    struct stat st;
    assert_int_equal(lstat(fifo, &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
    assert_int_equal(lstat(sub, &st), 0);
    assert_true(S_ISDIR(st.st_mode));
    assert_int_equal(lstat(link_, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_string_equal(slurp(target), "kept");
    char msg[256];
    assert_status(BTDF_EINVAL, btdf_output_check(fifo, msg, sizeof msg));
    assert_non_null(strstr(msg, "not a regular file"));
    assert_status(BTDF_EINVAL, btdf_output_check(sub, msg, sizeof msg));
    assert_non_null(strstr(msg, "folder"));
    assert_status(BTDF_OK, btdf_output_check(target, msg, sizeof msg));
    /* 4 files, no temporary left beside them */
    assert_int_equal(entries(), 4);
    unlink(fifo);
    rmdir(sub);
    unlink(link_);
    unlink(target);
}

static void missing_folder(void **state)
{
    (void)state;
    char p[512], msg[256];
    at(p, sizeof p, "nowhere/r.json");
    assert_status(BTDF_EIO, btdf_output_check(p, msg, sizeof msg));
    assert_non_null(strstr(msg, "nowhere"));
    assert_status(BTDF_EIO, put(p, "x"));
}

/* A pid that certainly belonged to a process that is gone: a reaped child. */
static long dead_pid(void)
{
    pid_t c = fork();
    if (c == 0)
        _exit(0);
    int ws;
    waitpid(c, &ws, 0);
    return (long)c;
}

static void stale_temporaries_removed(void **state)
{
    (void)state;
    long gone = dead_pid();
    char stale[512], live[512], other[512], out[512], name[128];
    snprintf(name, sizeof name, ".x.csv.tmp%ld-7.csv", gone);
    at(stale, sizeof stale, name);
    snprintf(name, sizeof name, ".x.csv.tmp%ld-7.csv", (long)getppid()); /* alive */
    at(live, sizeof live, name);
    at(other, sizeof other, ".x.csv.tmpnotapid-7.csv");
    at(out, sizeof out, "x.csv");
    assert_int_equal(btdf_tmp_name_pid(strrchr(stale, '/') + 1), gone);
    assert_int_equal(btdf_tmp_name_pid("x.csv"), 0);
    assert_int_equal(btdf_tmp_name_pid(".x.tmp12-3.c-v"), 0);
    assert_int_equal(btdf_tmp_name_pid(".x.tmp.tmp12-3"), 12);
    raw(stale, "s");
    raw(live, "l");
    raw(other, "o");
    assert_int_equal(access(stale, F_OK), 0);
    assert_status(BTDF_OK, put(out, "new"));
    assert_int_equal(access(stale, F_OK), -1);
    assert_int_equal(access(live, F_OK), 0);
    assert_int_equal(access(other, F_OK), 0);
    assert_string_equal(slurp(out), "new");
    unlink(live);
    unlink(other);
    unlink(out);
}

static void longest_names(void **state)
{
    (void)state;
    for (size_t len = 240; len <= 255; len++) {
        char name[300], p[800];
        memset(name, 'a', len);
        memcpy(name + len - 4, ".csv", 5);
        at(p, sizeof p, name);
        assert_status(BTDF_OK, put(p, "long"));
        assert_string_equal(slurp(p), "long");
        unlink(p);
    }
    assert_int_equal(entries(), 0);
    char name[300], p[800], msg[256];
    memset(name, 'b', 256);
    name[256] = 0;
    at(p, sizeof p, name);
    assert_status(BTDF_EINVAL, btdf_output_check(p, msg, sizeof msg));
}

static void group_together_or_not_at_all(void **state)
{
    (void)state;
    char a[512], b[512], c[512], msg[256];
    at(a, sizeof a, "a.csv");
    at(b, sizeof b, "b.png");
    at(c, sizeof c, "c.json");
    /* success: nothing appears before the commit, everything after */
    btdf_tmp_group_begin();
    assert_status(BTDF_OK, put(a, "A1"));
    assert_status(BTDF_OK, put(b, "B1"));
    assert_int_equal(access(a, F_OK), -1);
    assert_int_equal(access(b, F_OK), -1);
    assert_status(BTDF_OK, btdf_tmp_group_commit(msg, sizeof msg));
    assert_string_equal(slurp(a), "A1");
    assert_string_equal(slurp(b), "B1");
    assert_int_equal(entries(), 2);
    /* one failing write: the earlier files stay as they were, nothing new appears */
    btdf_tmp_group_begin();
    assert_status(BTDF_OK, put(a, "A2"));
    assert_status(BTDF_EIO, btdf_write_file_atomic(c, ".json", failing_writer, NULL, msg,
                                                     sizeof msg));
    assert_status(BTDF_OK, put(b, "B2"));
    assert_status(BTDF_EIO, btdf_tmp_group_commit(msg, sizeof msg));
    assert_string_equal(slurp(a), "A1");
    assert_string_equal(slurp(b), "B1");
    assert_int_equal(access(c, F_OK), -1);
    assert_int_equal(entries(), 2);
    /* an output that became a folder before the commit: none is renamed */
    btdf_tmp_group_begin();
    assert_status(BTDF_OK, put(a, "A3"));
    assert_status(BTDF_OK, put(c, "C3"));
    assert_int_equal(mkdir(c, 0700), 0);
    assert_status(BTDF_EINVAL, btdf_tmp_group_commit(msg, sizeof msg));
    assert_string_equal(slurp(a), "A1");
    rmdir(c);
    /* abort removes the finished temporaries */
    btdf_tmp_group_begin();
    assert_status(BTDF_OK, put(c, "C4"));
    btdf_tmp_group_abort();
    assert_int_equal(entries(), 2);
    /* outside a group, writes are immediate again */
    assert_status(BTDF_OK, put(c, "C5"));
    assert_string_equal(slurp(c), "C5");
    unlink(a);
    unlink(b);
    unlink(c);
}

static void same_file(void **state)
{
    (void)state;
    char a[512], a2[512], h[512], b[512];
    at(a, sizeof a, "s.csv");
    snprintf(a2, sizeof a2, "%s/./../%s/s.csv", dir, strrchr(dir, '/') + 1);
    at(h, sizeof h, "hard.csv");
    at(b, sizeof b, "t.csv");
    assert_true(btdf_same_file(a, a2)); /* neither exists yet */
    assert_false(btdf_same_file(a, b));
    assert_status(BTDF_OK, put(a, "x"));
    assert_int_equal(link(a, h), 0);
    assert_true(btdf_same_file(a, h));
    assert_true(btdf_same_file(a2, h));
    assert_false(btdf_same_file(a, b));
    unlink(a);
    unlink(h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(never_replaces_a_non_file),
        cmocka_unit_test(missing_folder),
        cmocka_unit_test(stale_temporaries_removed),
        cmocka_unit_test(longest_names),
        cmocka_unit_test(group_together_or_not_at_all),
        cmocka_unit_test(same_file),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
