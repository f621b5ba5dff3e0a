#!/usr/bin/env python3
"""Fails on a Catch2 TEST_CASE / SCENARIO / TEST_CASE_METHOD / SECTION name that contains ';'.

Why: ctest's Catch discovery (catch_discover_tests) passes each test name through a CMake list,
where ';' separates elements, so a name with ';' becomes several ctest entries, none of which
names a test (each runs no test and passes). Write ', ' or ' - ' instead.

The name is the macro's first string argument (TEST_CASE_METHOD: the one after the fixture);
adjacent literals ("a " "b") are joined, so a ';' in a continuation line is found too. Comments
and preprocessor lines are skipped; a macro whose name is not a literal is ignored.

Usage: test_names.py ROOT...  (each ROOT a folder, scanned for .cc / .h / .cpp / .hpp except
       build*/, hidden folders and this lint's fixtures (lint/fixtures/), or a file)
Exit 0 when no name has ';', 1 otherwise (one line per name: path:line: macro("name")), 2 on
bad use.
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import long_functions  # noqa: E402  (its strip_code: comments, literals, preprocessor lines)

SUFFIXES = (".cc", ".h", ".cpp", ".hpp")
MACROS = ("TEST_CASE", "SCENARIO", "TEST_CASE_METHOD", "SECTION", "DYNAMIC_SECTION")
MACRO_RE = re.compile(r"\b(%s)\s*\(" % "|".join(MACROS))
FIXTURES = os.path.join(os.path.dirname(os.path.realpath(__file__)), "fixtures")
LITERAL_RE = re.compile(r'\s*"((?:[^"\\\n]|\\.)*)"')


def test_names(text):
  """Yields (line, macro, name) for every test / section named by a string literal."""
  # Macros are found in the code with comments, literals and preprocessor lines blanked (same
  # positions); the name's literals are then read from the text.
  code = long_functions.strip_code(text)
  for m in MACRO_RE.finditer(code):
    pos = m.end()
    if m.group(1) == "TEST_CASE_METHOD":
      comma = code.find(",", pos)
      if comma < 0:
        continue
      pos = comma + 1
    parts = []
    while True:
      lit = LITERAL_RE.match(text, pos)
      if not lit or code[lit.start(1) - 1] != '"':
        break
      parts.append(lit.group(1))
      pos = lit.end()
    if parts:
      yield code.count("\n", 0, m.start()) + 1, m.group(1), "".join(parts)


def files_under(root):
  if os.path.isfile(root):
    yield root
    return
  for dirpath, dirnames, filenames in os.walk(root):
    dirnames[:] = sorted(d for d in dirnames if not d.startswith((".", "build")) and
                         os.path.realpath(os.path.join(dirpath, d)) != FIXTURES)
    for f in sorted(filenames):
      if f.endswith(SUFFIXES):
        yield os.path.join(dirpath, f)


def main(argv):
  if not argv or any(a.startswith("-") for a in argv):
    print("usage: test_names.py ROOT...", file=sys.stderr)
    return 2
  bad, names = [], 0
  for root in argv:
    if not os.path.exists(root):
      print("test_names: %s does not exist" % root, file=sys.stderr)
      return 2
    for path in files_under(root):
      with open(path, encoding="utf-8", errors="replace") as f:
        text = f.read()
      for line, macro, name in test_names(text):
        names += 1
        if ";" in name:
          bad.append('%s:%d: %s("%s") has \';\': ctest\'s Catch discovery splits the name '
                     "there into entries that run no test; write ', ' or ' - '"
                     % (path, line, macro, name))
  for line in bad:
    print(line)
  print("test_names: %d names, %d with ';'" % (names, len(bad)))
  return 1 if bad else 0


if __name__ == "__main__":
  sys.exit(main(sys.argv[1:]))
