/* SPDX-License-Identifier: MIT */
/* test_tmpfaults.c: output groups under injected faults. src/tmpfile.c is built into this
   test with BTDF_TMP_SEAM, which routes its link and rename calls through the two
   functions below: links refused as FAT, network and FUSE file systems refuse them, a
   rename failing, a signal arriving in the middle of a commit. */
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "btdf_test.h"
#include "io/tmpfile.h"

int tmp_seam_link(const char *from, const char *to);
int tmp_seam_rename(const char *from, const char *to);

static char dir[256];
static int link_errno;            /* link fails with this errno when non-zero */
static const char *rename_fails;  /* a rename onto a path ending so fails with EIO */
static int signal_after = -1;     /* SIGINT raised after this many renames into place */
static int call_handler_after = -1; /* tmp_remove_all called as from another thread */
static volatile sig_atomic_t renames, renames_seen_by_handler = -1;

static int ends_with(const char *s, const char *tail)
{
    size_t a = strlen(s), b = strlen(tail);
    return a >= b && !strcmp(s + a - b, tail);
}

int tmp_seam_link(const char *from, const char *to)
{
    if (link_errno) {
        errno = link_errno;
        return -1;
    }
    return link(from, to);
}

int tmp_seam_rename(const char *from, const char *to)
{
    if (rename_fails && ends_with(to, rename_fails)) {
        errno = EIO;
        return -1;
    }
    int r = rename(from, to);
    if (r == 0 && !strstr(to, ".btdfbak")) {
        renames++;
        if (renames == signal_after)
            raise(SIGINT);
        if (renames == call_handler_after) {
            call_handler_after = -1;
            tmp_remove_all();
        }
    }
    return r;
}

static void on_sigint(int sig)
{
    (void)sig;
    renames_seen_by_handler = renames;
    tmp_remove_all(); /* what btdftab's handler does before it dies */
}

static int setup(void **state)
{
    (void)state;
    link_errno = 0;
    rename_fails = NULL;
    signal_after = call_handler_after = -1;
    renames = 0;
    renames_seen_by_handler = -1;
    return btdf_test_mkdtemp(dir, sizeof dir, "tmpfaults");
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

static const char *slurp(const char *path)
{
    static char buf[256];
    FILE *f = fopen(path, "rb");
    if (!f)
        return "(missing)";
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

/* a.csv and a.json of a first run, then a second run's pair in a group */
static void first_run(char *a, char *j)
{
    at(a, 512, "a.csv");
    at(j, 512, "a.json");
    char msg[256];
    tmp_group_begin();
    assert_int_equal(put(a, "A1"), BTDF_OK);
    assert_int_equal(put(j, "J1"), BTDF_OK);
    assert_int_equal(tmp_group_commit(msg, sizeof msg), BTDF_OK);
    tmp_group_begin();
    assert_int_equal(put(a, "A2"), BTDF_OK);
    assert_int_equal(put(j, "J2"), BTDF_OK);
}

/* Links refused (EPERM): the report's rename failing still puts the earlier table back. */
static void rollback_without_links(void **state)
{
    (void)state;
    char a[512], j[512], msg[256] = "";
    first_run(a, j);
    link_errno = EPERM;
    rename_fails = "a.json";
    assert_int_equal(tmp_group_commit(msg, sizeof msg), BTDF_EIO);
    assert_non_null(strstr(msg, "a.json"));
    assert_string_equal(slurp(a), "A1");
    assert_string_equal(slurp(j), "J1");
    assert_int_equal(entries(), 2); /* no temporary, no copy left behind */
}

/* The same with links: the earlier files come back as they were. */
static void rollback_with_links(void **state)
{
    (void)state;
    char a[512], j[512], msg[256] = "";
    first_run(a, j);
    rename_fails = "a.json";
    assert_int_equal(tmp_group_commit(msg, sizeof msg), BTDF_EIO);
    assert_string_equal(slurp(a), "A1");
    assert_string_equal(slurp(j), "J1");
    assert_int_equal(entries(), 2);
}

/* SIGINT after the first rename of a commit: the handler runs once the whole group is in
   place, so a.csv and a.json are both of the second run. */
static void sigint_during_commit(void **state)
{
    (void)state;
    char a[512], j[512], msg[256] = "";
    struct sigaction sa, old;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    assert_int_equal(sigaction(SIGINT, &sa, &old), 0);
    first_run(a, j);
    signal_after = 3; /* the first run made two */
    assert_int_equal(tmp_group_commit(msg, sizeof msg), BTDF_OK);
    sigaction(SIGINT, &old, NULL);
    assert_int_equal(renames_seen_by_handler, 4);
    assert_string_equal(slurp(a), "A2");
    assert_string_equal(slurp(j), "J2");
    assert_int_equal(entries(), 2);
}

/* A handler running in another thread (where the commit's mask does not reach) while the
   group is renamed: it completes the renames rather than leave half of the group new. */
static void handler_elsewhere_completes_the_group(void **state)
{
    (void)state;
    char a[512], j[512], msg[256] = "";
    first_run(a, j);
    call_handler_after = 3;
    tmp_group_commit(msg, sizeof msg);
    assert_string_equal(slurp(a), "A2");
    assert_string_equal(slurp(j), "J2");
    assert_int_equal(entries(), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(rollback_without_links, setup, teardown),
        cmocka_unit_test_setup_teardown(rollback_with_links, setup, teardown),
        cmocka_unit_test_setup_teardown(sigint_during_commit, setup, teardown),
        cmocka_unit_test_setup_teardown(handler_elsewhere_completes_the_group, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
