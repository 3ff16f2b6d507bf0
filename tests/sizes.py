#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""sizes.py ROOT: the size rule of src/README.md. No C file of src/, formats/ or tools/
above MAX_FILE lines and no function above MAX_FUNC lines, unless the comment just
above it says why, in the form "Long: <reason>" (a file: in its first comment)."""
import os
import re
import sys

MAX_FILE = 800
MAX_FUNC = 150
# A function definition: a line at column 0 that opens a brace, after a signature.
SIG_END = re.compile(r'\)\s*$')
NAME = re.compile(r'([A-Za-z_][A-Za-z0-9_]*)\s*\(')


def comment_above(lines, i):
    """The comment block that ends just before line i (the signature's first line)."""
    j = i - 1
    text = []
    while j >= 0 and lines[j].strip() and not lines[j].startswith('}'):
        text.append(lines[j])
        if lines[j].lstrip().startswith('/*'):
            break
        j -= 1
    return '\n'.join(reversed(text))


def check(path, rel, bad):
    with open(path, encoding='utf-8') as fh:
        lines = fh.read().split('\n')
    head = '\n'.join(lines[:12])
    if len(lines) > MAX_FILE and 'Long:' not in head:
        bad.append(f'{rel}: {len(lines)} lines (at most {MAX_FILE}, or say why: "Long: ...")')
    i, funcs = 0, 0
    while i < len(lines):
        if lines[i].startswith('{') and i > 0:
            s = i - 1  # the signature's first line: back to the line naming the function
            while s > 0 and not NAME.search(lines[s]):
                s -= 1
            while s > 0 and lines[s - 1].strip() and not lines[s - 1].rstrip().endswith(
                    (';', '*/', '}')) and not lines[s - 1].startswith('#'):
                s -= 1
            e = i + 1
            while e < len(lines) and not lines[e].startswith('}'):
                e += 1
            n = e - i + 1
            funcs += 1
            m = NAME.search(' '.join(lines[s:i]))
            name = m.group(1) if m else '?'
            if n > MAX_FUNC and 'Long:' not in comment_above(lines, s):
                bad.append(f'{rel}:{s + 1}: {name} is {n} lines (at most {MAX_FUNC}, or say '
                           f'why in its comment: "Long: ...")')
            i = e
        i += 1
    return funcs


def main(root):
    bad, nfiles, nfuncs = [], 0, 0
    for top in ('src', 'formats', 'tools'):
        for d, _, names in os.walk(os.path.join(root, top)):
            for name in sorted(names):
                if name.endswith(('.c', '.h')):
                    path = os.path.join(d, name)
                    nfiles += 1
                    nfuncs += check(path, os.path.relpath(path, root), bad)
    if nfiles < 50 or nfuncs < 500:  # a tree where nothing was read proves nothing
        bad.append(f'only {nfiles} files and {nfuncs} functions under {root}: wrong root?')
    for b in bad:
        print(b)
    print(f'{nfiles} files, {nfuncs} functions checked, {len(bad)} against the rule')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else '.'))
