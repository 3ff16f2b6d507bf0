/* SPDX-License-Identifier: MIT */
/* test_files.c: the atomic writer never replaces what is not a file, cleans up after
   killed processes, takes any legal name, and commits groups of outputs together. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
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
    io_bytes b = {text, strlen(text)};
    char msg[256];
    return io_write_file_atomic(path, ".txt", io_write_bytes, &b, msg, sizeof msg);
}

static btdf_status failing_writer(void *ctx, FILE *f, const char *tmp, char *msg,
                                  size_t msglen)
{
    (void)ctx;
    (void)tmp;
    fputs("half", f);
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

/* A file of our scheme's shape, last changed age seconds ago. */
static void aged(const char *path, const char *text, long age)
{
    raw(path, text);
    struct timespec t[2];
    clock_gettime(CLOCK_REALTIME, &t[0]);
    t[0].tv_sec -= age;
    t[1] = t[0];
    assert_int_equal(utimensat(AT_FDCWD, path, t, 0), 0);
}

/* Only abandoned temporaries of our own are removed: our name's shape, this user's, over
   a minute old and locked by no writer. A live writer's lock protects it whatever its
   PID (another PID namespace gives no PID to test); look-alike names of users never go. */
static void stale_temporaries_removed(void **state)
{
    (void)state;
    char stale[512], live[512], fresh[512], u1[512], u2[512], u3[512], out[512];
    at(stale, sizeof stale, ".x.csv.btdftmp0123456789abcdef.csv");
    at(live, sizeof live, ".x.csv.btdftmpfedcba9876543210.csv");
    at(fresh, sizeof fresh, ".x.csv.btdftmp00000000000000aa.csv");
    at(u1, sizeof u1, ".mydata.tmp4000000-0.txt");
    at(u2, sizeof u2, ".backup.tmp3999999-12");
    at(u3, sizeof u3, ".x.csv.btdftmp0123.csv"); /* not sixteen digits */
    at(out, sizeof out, "x.csv");
    assert_true(tmp_name_ours(strrchr(stale, '/') + 1));
    assert_false(tmp_name_ours("x.csv"));
    assert_false(tmp_name_ours(".mydata.tmp4000000-0.txt"));
    assert_false(tmp_name_ours(".x.btdftmp0123456789abcdef.c-v"));
    assert_false(tmp_name_ours(".btdftmp0123456789abcdef.csv"));
    aged(stale, "s", 3600);
    aged(live, "l", 3600);
    aged(fresh, "f", 0);
    aged(u1, "1", 3600);
    aged(u2, "2", 3600);
    aged(u3, "3", 3600);
    /* the live writer: another process holding the lock, as a writer does */
    int ready[2];
    assert_int_equal(pipe(ready), 0);
    pid_t child = fork();
    if (child == 0) {
        int fd = open(live, O_RDWR);
        char c = flock(fd, LOCK_EX) == 0 ? 'y' : 'n';
        if (write(ready[1], &c, 1) != 1)
            _exit(1);
        pause();
        _exit(0);
    }
    char c = 0;
    assert_int_equal(read(ready[0], &c, 1), 1);
    assert_int_equal(c, 'y');
    assert_status(BTDF_OK, put(out, "new"));
    kill(child, SIGKILL);
    waitpid(child, NULL, 0);
    close(ready[0]);
    close(ready[1]);
    assert_int_equal(access(stale, F_OK), -1);
    assert_int_equal(access(live, F_OK), 0);
    assert_int_equal(access(fresh, F_OK), 0);
    assert_int_equal(access(u1, F_OK), 0);
    assert_int_equal(access(u2, F_OK), 0);
    assert_int_equal(access(u3, F_OK), 0);
    assert_string_equal(slurp(out), "new");
    /* once its writer is gone, the lock goes with it and the next write removes it */
    assert_status(BTDF_OK, put(out, "newer"));
    assert_int_equal(access(live, F_OK), -1);
    unlink(fresh);
    unlink(u1);
    unlink(u2);
    unlink(u3);
    unlink(out);
}

/* Symbolic links planted at names a writer might choose are never followed: the names
   are not predictable, and the file is created with O_EXCL|O_NOFOLLOW. The names an
   earlier scheme made from the PID and a counter from 0 are planted here. */
static void planted_links_not_followed(void **state)
{
    (void)state;
    char victim[512], out[512], name[128], plant[20][512];
    at(victim, sizeof victim, "victim.txt");
    at(out, sizeof out, "x.csv");
    raw(victim, "precious");
    for (int k = 0; k < 20; k++) {
        snprintf(name, sizeof name, ".x.csv.tmp%ld-%d.txt", (long)getpid(), k);
        at(plant[k], sizeof plant[k], name);
        assert_int_equal(symlink(victim, plant[k]), 0);
    }
    for (int k = 0; k < 3; k++)
        assert_status(BTDF_OK, put(out, "table"));
    assert_string_equal(slurp(victim), "precious");
    struct stat st;
    assert_int_equal(lstat(out, &st), 0);
    assert_true(S_ISREG(st.st_mode));
    assert_string_equal(slurp(out), "table");
    /* two names drawn for the same output differ in their sixteen random digits */
    char t1[600], t2[600];
    int s1 = tmp_begin(out, ".csv", t1, sizeof t1);
    int s2 = tmp_begin(out, ".csv", t2, sizeof t2);
    assert_true(s1 >= 0 && s2 >= 0);
    tmp_end(s1);
    tmp_end(s2);
    assert_string_not_equal(t1, t2);
    assert_true(tmp_name_ours(strrchr(t1, '/') + 1));
    /* the mode is 0666 less the umask, as fopen gives */
    mode_t old = umask(027);
    assert_status(BTDF_OK, put(out, "masked"));
    umask(old);
    assert_int_equal(stat(out, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0640);
    for (int k = 0; k < 20; k++)
        unlink(plant[k]);
    unlink(victim);
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
    tmp_group_begin();
    assert_status(BTDF_OK, put(a, "A1"));
    assert_status(BTDF_OK, put(b, "B1"));
    assert_int_equal(access(a, F_OK), -1);
    assert_int_equal(access(b, F_OK), -1);
    assert_status(BTDF_OK, tmp_group_commit(msg, sizeof msg));
    assert_string_equal(slurp(a), "A1");
    assert_string_equal(slurp(b), "B1");
    assert_int_equal(entries(), 2);
    /* one failing write: the earlier files stay as they were, nothing new appears */
    tmp_group_begin();
    assert_status(BTDF_OK, put(a, "A2"));
    assert_status(BTDF_EIO, io_write_file_atomic(c, ".json", failing_writer, NULL, msg,
                                                     sizeof msg));
    assert_status(BTDF_OK, put(b, "B2"));
    assert_status(BTDF_EIO, tmp_group_commit(msg, sizeof msg));
    assert_string_equal(slurp(a), "A1");
    assert_string_equal(slurp(b), "B1");
    assert_int_equal(access(c, F_OK), -1);
    assert_int_equal(entries(), 2);
    /* an output that became a folder before the commit: none is renamed */
    tmp_group_begin();
    assert_status(BTDF_OK, put(a, "A3"));
    assert_status(BTDF_OK, put(c, "C3"));
    assert_int_equal(mkdir(c, 0700), 0);
    assert_status(BTDF_EINVAL, tmp_group_commit(msg, sizeof msg));
    assert_string_equal(slurp(a), "A1");
    rmdir(c);
    /* abort removes the finished temporaries */
    tmp_group_begin();
    assert_status(BTDF_OK, put(c, "C4"));
    tmp_group_abort();
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
        cmocka_unit_test(planted_links_not_followed),
        cmocka_unit_test(never_replaces_a_non_file),
        cmocka_unit_test(missing_folder),
        cmocka_unit_test(stale_temporaries_removed),
        cmocka_unit_test(longest_names),
        cmocka_unit_test(group_together_or_not_at_all),
        cmocka_unit_test(same_file),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
