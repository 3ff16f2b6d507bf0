# SPDX-License-Identifier: MIT
"""readme_c.py README.md OUT.c: the README's C example as a program, so it is compiled
and run by the tests (tests/meson.build) and cannot drift from the library.

The block is the first ```c block after the heading "## The C API": its #include lines go
to the top, the rest into main(). With an argument the program runs the block with a
build that fails (smoothness -1, refused by btdf_table_build), the path on which the
example must not touch a table it never got.
"""
import sys

text = open(sys.argv[1], encoding="utf-8").read()
start = text.index("## The C API")
body = text[text.index("```c\n", start) + 5:]
body = body[:body.index("```")]
heads = [ln for ln in body.splitlines() if ln.startswith("#")]
code = [ln for ln in body.splitlines() if not ln.startswith("#")]
out = ["/* Generated from README.md by tests/readme_c.py: do not edit. */"] + heads + [
    "static int readme_fail;",
    "static btdf_status readme_build(const btdf_table_opts *o, btdf_table **t, char *m,",
    "                                size_t n)",
    "{",
    "    btdf_table_opts bad = *o;",
    "    bad.params.smoothness = -1; /* refused: the failing path */",
    "    return btdf_table_build(readme_fail ? &bad : o, t, m, n);",
    "}",
    "#define btdf_table_build readme_build",
    "int main(int argc, char **argv)",
    "{",
    "    (void)argv;",
    "    readme_fail = argc > 1;",
] + ["    " + ln for ln in code] + ["    return 0;", "}"]
with open(sys.argv[2], "w", encoding="utf-8") as f:
    f.write("\n".join(out) + "\n")
