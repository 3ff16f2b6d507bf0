#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The include rule of src/README.md, executable: every project include of src/,
formats/ and tools/ must go down the layers (or stay in its folder). Usage:
layering.py SOURCE_ROOT. Exit 0 when every edge is allowed, 1 otherwise."""
import os, re, sys

# folder -> folders it may include besides itself (include/btdf/ is open to all).
ALLOWED = {
    'core': set(),
    'io': {'core'},
    'model': {'core'},
    'estimate': {'core', 'model'},
    'table': {'core', 'model', 'estimate'},
    'scatfun': {'core', 'model', 'estimate'},
    'radiance': {'core', 'model', 'estimate'},
    'sim': {'core', 'io', 'model', 'estimate'},  # the simulator (src/sim/)
    'preview': {'core', 'model', 'table'},
    'formats': {'core', 'io', 'model', 'formats', 'table', 'scatfun', 'radiance'},
}
# formats/ sees only the object headers of table, scatfun and radiance.
FORMATS_OBJECTS = {'table/table.h', 'scatfun/scatfun.h', 'radiance/radiance.h'}
# Public headers: include/btdf/ and the generated configuration.
PUBLIC = {'btdf.h', 'btdf_io.h', 'btdf_preview.h', 'btdf_radiance.h', 'btdf_scatfun.h',
          'btdf_sim.h', 'btdf_config.h'}
# System headers confined to one place (layout: STYLE section 9).
# FFTW: the .bsdf builder's cosine transforms, and the simulator's spectral filter that
# makes its Gaussian surfaces (src/sim/surface.c).
CONFINED = {'fftw3.h': ('src/scatfun/dct.c', 'src/sim/surface.c'),
            'openexr.h': ('formats/exr.c', 'formats/exr_impl.h', 'formats/exr_read.c',
                          'formats/exr_write.c'), 'png.h': ('formats/png.c',)}

INC = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.M)


def folder_of(rel):
    parts = rel.split('/')
    if parts[0] == 'src':
        return parts[1] if len(parts) > 2 else '?' + parts[1]  # src/ has no loose files
    return parts[0]


def main(root):
    bad, count = [], 0
    for top in ('src', 'formats', 'tools'):
        for d, _, names in os.walk(os.path.join(root, top)):
            for name in sorted(names):
                if not name.endswith(('.c', '.h')):
                    continue
                rel = os.path.relpath(os.path.join(d, name), root).replace(os.sep, '/')
                here = folder_of(rel)
                if here.startswith('?'):
                    bad.append(f'{rel}: a file loose in src/: give it its folder')
                with open(os.path.join(d, name), encoding='utf-8') as fh:
                    text = fh.read()
                for kind, target in INC.findall(text):
                    count += 1
                    base = target.split('/')[-1]
                    if kind == '<':
                        if base in CONFINED and rel not in CONFINED[base]:
                            bad.append(f'{rel}: <{target}> belongs in {CONFINED[base]}')
                        if target.startswith('cairo') and here != 'preview':
                            bad.append(f'{rel}: <{target}>: cairo only in preview/')
                        continue
                    if target in PUBLIC:
                        continue
                    if here == 'tools':
                        if '/' in target and not name.startswith('bench'):
                            bad.append(f'{rel}: "{target}": tools/ sees include/btdf/ only')
                        continue  # tools' own headers ("run.h") are its folder
                    if '/' in target:
                        to = target.split('/')[0]
                    else:
                        bad.append(f'{rel}: "{target}": name the folder')
                        continue
                    if to == here:
                        continue
                    if to in ('tools',) or (to == 'formats' and here != 'formats'):
                        bad.append(f'{rel}: "{target}": nothing in src/ includes {to}/')
                    elif to not in ALLOWED.get(here, set()):
                        bad.append(f'{rel}: "{target}": {here}/ may not include {to}/')
                    elif here == 'formats' and to in ('table', 'scatfun', 'radiance') \
                            and target not in FORMATS_OBJECTS:
                        bad.append(f'{rel}: "{target}": formats/ sees object headers only')
    # Self-check: a tree where nothing was read proves nothing.
    if count < 100:
        bad.append(f'only {count} includes found under {root}: wrong source root?')
    for b in bad:
        print(b)
    print(f'{count} includes checked, {len(bad)} against the rule')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else '.'))
