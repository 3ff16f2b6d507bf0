/* SPDX-License-Identifier: MIT */
/* test_pathnorm.c: output paths that name one file, before and after their folders exist
   (tools/pathnorm.c, which the manifest's duplicate check uses). */
#define _XOPEN_SOURCE 700 /* realpath */
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "btdf_test.h"
#include "pathnorm.h"

static char dir[256];

static void at(char *out, size_t len, const char *name)
{
    snprintf(out, len, "%s/%s", dir, name);
}

static void same(const char *x, const char *y, int want)
{
    char a[600], b[600];
    at(a, sizeof a, x);
    at(b, sizeof b, y);
    if (path_same(a, b) != want) {
        print_error("'%s' and '%s': expected %s\n", x, y, want ? "same" : "different");
        fail();
    }
}

static void before_and_after_folders_exist(void **state)
{
    (void)state;
    /* none of nd, o, d exists */
    same("nd/x.csv", "nd//x.csv", 1);
    same("o/./x.bsdf", "o/x.bsdf", 1);
    same("d/../d/x.csv", "d/x.csv", 1);
    same("d/x.csv", "d/y.csv", 0);
    same("d/x.csv", "e/x.csv", 0);
    same("a/b/../../d/x.csv", "d/x.csv", 1);
    /* with a link among the existing folders: its target is followed */
    char real[600], link_[600];
    at(real, sizeof real, "real");
    at(link_, sizeof link_, "link");
    assert_int_equal(mkdir(real, 0700), 0);
    assert_int_equal(symlink(real, link_), 0);
    same("link/new/x.csv", "real/new//x.csv", 1);
    same("link/../x.csv", "x.csv", 1); /* real/.. is dir */
    same("d/../d/x.csv", "d/x.csv", 1);
    unlink(link_);
    rmdir(real);
    /* a relative name against the absolute one */
    char cwd[512], a[600], b[700];
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(dir), 0);
    snprintf(b, sizeof b, "%s/nd/x.csv", dir);
    assert_true(path_same("nd//./x.csv", b));
    assert_true(path_normalise("nd//./x.csv", a, sizeof a));
    assert_int_equal(chdir(cwd), 0);
    assert_null(strstr(a, "//"));
}

int main(void)
{
    if (btdf_test_mkdtemp(dir, sizeof dir, "pathnorm") != 0)
        return 1;
    /* the folder itself canonical, so links in TMPDIR do not matter */
    char *r = realpath(dir, NULL);
    if (r) {
        snprintf(dir, sizeof dir, "%s", r);
        free(r);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(before_and_after_folders_exist),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    btdf_test_rmtree(dir);
    return rc;
}
