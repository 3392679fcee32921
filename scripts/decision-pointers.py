#!/usr/bin/env python3
"""Checks that every pointer into docs/decisions.md names one of its `## ` headings exactly.

A pointer is `decisions.md` (optionally as a Markdown link, optionally followed by `)` and a
comma) followed by a quoted title; comment markers at line starts are removed and lines joined,
so a pointer wrapped across comment lines is read whole. Inside docs/decisions.md, every
curly-quoted cross-reference is checked against the headings as well. Exits 1 on a problem:

  python3 scripts/decision-pointers.py
"""
import re, subprocess, sys

root = subprocess.check_output(['git', 'rev-parse', '--show-toplevel'], text=True).strip()
dec = open(f'{root}/docs/decisions.md', encoding='utf-8').read()
titles = set(re.findall(r'(?m)^## (.+?)\s*$', dec))
files = subprocess.check_output(['git', 'ls-files'], cwd=root, text=True).split()
pointer = re.compile(r'decisions\.md(?:\]\(decisions\.md\))?\)?\s*,\s*([“"])(.+?)([”"])')
prefix = re.compile(r'^\s*(?://[!/]?|#|\*)?\s?')
bad = 0
count = 0
for f in files:
    if f == 'docs/decisions.md' or not re.search(r'\.(rs|wgsl|md|py|sh|toml)$', f):
        continue
    try:
        lines = open(f'{root}/{f}', encoding='utf-8').read().split('\n')
    except (UnicodeDecodeError, IsADirectoryError):
        continue
    text = ' '.join(prefix.sub('', l, count=1).strip() for l in lines)
    for m in pointer.finditer(text):
        count += 1
        title = re.sub(r'\s+', ' ', m.group(2))
        if m.group(1) != '“' or m.group(3) != '”':
            print(f'{f}: straight quotes: {m.group(0)}')
            bad += 1
        if title not in titles:
            print(f'{f}: no heading “{title}”')
            bad += 1
    # a mention of decisions.md followed by a title-like quote we did not parse
    for m in re.finditer(r'decisions\.md[^.;]{0,40}?[“"]', text):
        if not pointer.match(text, m.start()):
            print(f'{f}: unparsed pointer: {text[m.start():m.start()+80]}')
            bad += 1
inner = 0
for t in re.findall(r'“([^”]+)”', dec):
    inner += 1
    if t not in titles:
        print(f'docs/decisions.md: no heading “{t}”')
        bad += 1
print(f'{count} pointers in the repository, {inner} cross-references in docs/decisions.md, '
      f'{len(titles)} headings; {bad} problems')
sys.exit(1 if bad else 0)
