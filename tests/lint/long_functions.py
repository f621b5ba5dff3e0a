#!/usr/bin/env python3
"""Lists every function body in the project's C++ sources longer than a limit (default 80 lines).

The rule (issue 10 point 4): no function over ~80 lines without a reason in a comment. A
function may exceed the limit only with `// long-function: REASON` (REASON not empty) on one of
the 3 lines above its signature.

How functions are found: a small lexer drops comments, string / character literals (raw strings
too) and preprocessor lines, then follows the braces. A `{` opens a function body when the text
before it (back to the previous `;`, `{` or `}` of the same scope) has a parameter list and is not
a namespace, class / struct / union / enum, `extern "C"` block or an initialiser (`= {`, `T x{`);
a namespace-scope lambda (`auto f = [](...) {`) counts as a function. Class bodies are followed
inside, so inline member functions are measured; everything inside a function body (lambdas,
local classes) counts towards that function. The body's length is the number of lines strictly
between the line of its `{` and the line of its `}`.

Usage: long_functions.py ROOT [--allow FILE] [--limit N] [--list]
  ROOT     the source tree; scans its .cc / .h / .cpp / .hpp files except build*/, .git/,
           tests/js/, tests/lint/fixtures/ and any third_party / external / node_modules folder
  --allow  a file of `path:Name` lines (path relative to ROOT, '#' comments): functions allowed
           to stay long for now. An entry that names no long function is an error too (a split
           removes its entry).
  --list   print every long function (with or without a reason) and exit 0
Exit 0 when every long function has a reason or an allow-list entry, 1 otherwise, 2 on bad use.
"""

import argparse
import os
import re
import sys

SUFFIXES = (".cc", ".h", ".cpp", ".hpp")
SKIP_DIR_NAMES = {".git", "third_party", "third-party", "external", "node_modules"}
SKIP_REL_DIRS = {os.path.join("tests", "js"), os.path.join("tests", "lint", "fixtures")}
REASON_RE = re.compile(r"//\s*long-function:\s*(\S.*)$")
KEYWORDS_NOT_NAMES = {"if", "for", "while", "switch", "return", "sizeof", "decltype",
                      "alignof", "noexcept", "catch", "static_assert", "throw"}


class Function:
  def __init__(self, path, name, sig_line, open_line, close_line):
    self.path = path            # relative to the root, '/' separated
    self.name = name            # qualified as far as the source says (Class::Method)
    self.sig_line = sig_line    # 1-based line of the signature's first token
    self.open_line = open_line  # line of the body's '{'
    self.close_line = close_line
    self.reason = None

  @property
  def length(self):
    return self.close_line - self.open_line - 1

  @property
  def key(self):
    return "%s:%s" % (self.path, self.name)


def strip_code(text):
  """Returns text with comments, literals and preprocessor lines blanked by spaces: the same
  length and lines, so positions in it are positions in the source."""
  out = []
  i, n = 0, len(text)
  at_line_start = True
  while i < n:
    c = text[i]
    if at_line_start:
      j = i
      while j < n and text[j] in " \t":
        j += 1
      if j < n and text[j] == "#":
        # Preprocessor directive, with backslash continuations.
        while j < n and not (text[j] == "\n" and text[j - 1] != "\\"):
          j += 1
        out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
        i = j
        continue
      at_line_start = False
    if c == "\n":
      out.append(c)
      at_line_start = True
      i += 1
    elif text.startswith("//", i):
      j = text.find("\n", i)
      j = n if j < 0 else j
      out.append(" " * (j - i))
      i = j
    elif text.startswith("/*", i):
      j = text.find("*/", i + 2)
      j = n if j < 0 else j + 2
      out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
      i = j
    elif c == "R" and i + 1 < n and text[i + 1] == '"' and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
      m = re.match(r'R"([^()\\ ]{0,16})\(', text[i:])
      if not m:
        out.append(c)
        i += 1
        continue
      end = text.find(")" + m.group(1) + '"', i)
      j = n if end < 0 else end + len(m.group(1)) + 2
      out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
      i = j
    elif c in "\"'":
      if c == "'" and i > 0 and text[i - 1].isalnum():
        out.append(" ")  # digit separator (1'000'000)
        i += 1
        continue
      j = i + 1
      while j < n and text[j] != c and text[j] != "\n":
        j += 2 if text[j] == "\\" else 1
      j = min(j, n - 1)
      out.append(c + "".join(ch if ch == "\n" else " " for ch in text[i + 1:j]) + c)
      i = j + 1
    else:
      out.append(c)
      i += 1
  return "".join(out)


def head_kind(head):
  """What a '{' opens, from the code before it: 'scope' (namespace, class, extern), 'function',
  or 'other' (initialisers, enums, control blocks)."""
  h = " ".join(head.split())
  if not h:
    return "other"
  h = re.sub(r"^template\s*<.*?>\s*", "", h)  # good enough for the heads seen here
  if re.match(r"^(inline\s+)?namespace\b", h) or re.match(r'^extern\s*"\s*"$', h):
    return "scope"
  if re.match(r"^(typedef\s+)?enum\b", h):
    return "other"
  if re.match(r"^(class|struct|union)\b", h) and "(" not in h.split(":")[0]:
    return "scope"
  if "(" not in h:
    return "other"
  if re.search(r"=\s*\[", h) or h.startswith("["):
    return "function"  # namespace-scope lambda
  # '=' outside parentheses means an initialiser (operator= has '(' right after it).
  depth = 0
  for k, ch in enumerate(h):
    if ch in "([":
      depth += 1
    elif ch in ")]":
      depth -= 1
    elif ch == "=" and depth == 0:
      nxt = h[k + 1:k + 2]
      prev = h[k - 1:k]
      if prev not in "=!<>" and nxt != "=" and not re.search(r"operator\s*[^\s\w(]*$", h[:k]):
        return "other"
  if h.endswith(")") or re.search(r"\)\s*(const|override|final|noexcept|mutable|->.*|&|&&|\s)*$", h):
    return "function"
  if re.search(r"\)\s*:\s*", h):  # constructor with a member initialiser list
    return "function"
  return "other"


def function_name(head):
  h = " ".join(head.split())
  h = re.sub(r"^template\s*<.*?>\s*", "", h)
  m = re.search(r"([A-Za-z_~][\w:~]*)\s*=\s*\[", h)
  if m:
    return m.group(1)
  m = re.search(r"(operator\s*(\(\)|[^\s(]+))\s*\(", h)
  if m:
    pre = re.search(r"([\w:]*::)?\s*$", h[:m.start()])
    return (pre.group(1) or "") + m.group(1).replace(" ", "")
  for m in re.finditer(r"([A-Za-z_~][\w]*(?:\s*::\s*~?[A-Za-z_]\w*)*)\s*\(", h):
    name = m.group(1).replace(" ", "")
    if name.split("::")[-1] not in KEYWORDS_NOT_NAMES:
      return name
  return "?"


def scan_text(text, rel_path):
  """Returns (functions, error or None) for one file's text."""
  code = strip_code(text)
  lines = text.split("\n")
  functions = []
  # Stack of open braces: (kind, class_name or None, Function or None).
  stack = []
  head_start = 0
  line = 1
  i, n = 0, len(code)
  func_depth = 0  # > 0 while inside a function body
  while i < n:
    c = code[i]
    if c == "\n":
      line += 1
    elif c in ";{}" and func_depth == 0:
      if c == "{":
        head = code[head_start:i]
        if (re.search(r"\)\s*:(?!:)", head) and (code[i - 1].isalnum() or code[i - 1] in "_>")):
          # A member's brace initialiser in a constructor's initialiser list (b_{x}): part of
          # the head, not the body.
          depth = 1
          i += 1
          while i < n and depth:
            depth += {"{": 1, "}": -1}.get(code[i], 0)
            line += code[i] == "\n"
            i += 1
          continue
        kind = head_kind(head)
        if kind == "function":
          offset = len(head) - len(head.lstrip())
          sig_line = code.count("\n", 0, head_start + offset) + 1
          classes = [s[1] for s in stack if s[0] == "class" and s[1]]
          name = function_name(head)
          if name in ("TEST_CASE", "SCENARIO", "TEST_CASE_METHOD"):
            # Catch2 test cases are named by their first string argument.
            parts = []
            for m in re.finditer(r'"((?:[^"\\]|\\.)*)"', text[head_start:i]):
              if m.group(1).startswith("["):
                break  # the tags
              parts.append(m.group(1))
            name = '%s("%s")' % (name, "".join(parts))
          if classes and "::" not in name:
            name = "::".join(classes + [name])
          fn = Function(rel_path, name, sig_line, line, None)
          stack.append(("function", None, fn))
          func_depth = 1
        elif kind == "scope":
          h = " ".join(head.split())
          m = re.match(r"^(?:template\s*<.*?>\s*)?(?:class|struct|union)\s+(?:\w+\s+)*?([A-Za-z_]\w*)\s*(?:final\s*)?(?::|$)", h)
          stack.append(("class" if m else "namespace", m.group(1) if m else None, None))
        else:
          stack.append(("other", None, None))
          func_depth = 0
          # An initialiser or enum at namespace scope: skip to its closing brace.
          depth = 1
          i += 1
          while i < n and depth:
            if code[i] == "{":
              depth += 1
            elif code[i] == "}":
              depth -= 1
            elif code[i] == "\n":
              line += 1
            i += 1
          stack.pop()
          head_start = i
          continue
      elif c == "}":
        if not stack:
          return functions, "%s:%d: unbalanced '}'" % (rel_path, line)
        stack.pop()
      head_start = i + 1
    elif c == ":" and func_depth == 0 and code[i:i + 2] != "::" and code[i - 1:i] != ":":
      # Access specifiers (public:) end a head; a ':' in a constructor's initialiser list or a
      # base-clause must not, so only a bare access keyword resets it.
      if re.search(r"(^|[;{}\s])(public|private|protected)\s*$", code[head_start:i]):
        head_start = i + 1
    elif func_depth > 0:
      if c == "{":
        func_depth += 1
      elif c == "}":
        func_depth -= 1
        if func_depth == 0:
          fn = stack.pop()[2]
          fn.close_line = line
          functions.append(fn)
          head_start = i + 1
    i += 1
  if func_depth or any(s[0] != "namespace" and s[0] != "class" for s in stack):
    return functions, "%s: unbalanced braces at end of file" % rel_path
  if stack:
    return functions, "%s: unbalanced braces at end of file" % rel_path
  for fn in functions:
    for k in range(max(1, fn.sig_line - 3), fn.sig_line):
      m = REASON_RE.search(lines[k - 1])
      if m:
        fn.reason = m.group(1).strip()
  return functions, None


def source_files(root):
  for dirpath, dirnames, filenames in os.walk(root):
    rel_dir = os.path.relpath(dirpath, root)
    keep = []
    for d in sorted(dirnames):
      rel = os.path.normpath(os.path.join(rel_dir, d))
      if d in SKIP_DIR_NAMES or rel in SKIP_REL_DIRS or (rel_dir == "." and d.startswith("build")):
        continue
      keep.append(d)
    dirnames[:] = keep
    for f in sorted(filenames):
      if f.endswith(SUFFIXES):
        yield os.path.join(dirpath, f)


def read_allow_list(path):
  entries = []
  with open(path, encoding="utf-8") as f:
    for raw in f:
      entry = re.split(r"(?:^|\s)#", raw, 1)[0].strip()
      if entry:
        entries.append(entry)
  return entries


def main(argv):
  p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
  p.add_argument("root")
  p.add_argument("--allow")
  p.add_argument("--limit", type=int, default=80)
  p.add_argument("--list", action="store_true")
  args = p.parse_args(argv)
  if not os.path.isdir(args.root):
    print("long_functions: %s is not a folder" % args.root, file=sys.stderr)
    return 2
  allowed = read_allow_list(args.allow) if args.allow else []
  long_functions, errors, files = [], [], 0
  for path in source_files(args.root):
    files += 1
    rel = os.path.relpath(path, args.root).replace(os.sep, "/")
    with open(path, encoding="utf-8", errors="replace") as f:
      functions, error = scan_text(f.read(), rel)
    if error:
      errors.append(error)
    long_functions += [fn for fn in functions if fn.length > args.limit]
  long_functions.sort(key=lambda fn: -fn.length)
  if args.list:
    for line in errors:
      print(line)
    for fn in long_functions:
      print("%4d  %s:%d %s%s" % (fn.length, fn.path, fn.open_line, fn.name,
                                 "  (reason: %s)" % fn.reason if fn.reason else ""))
    return 0
  failures = []
  for fn in long_functions:
    if not fn.reason and fn.key not in allowed:
      failures.append("%s:%d: %s is %d lines (limit %d): split it into named steps, or put "
                      "'// long-function: REASON' on one of the 3 lines above its signature"
                      % (fn.path, fn.sig_line, fn.name, fn.length, args.limit))
  long_keys = {fn.key for fn in long_functions if not fn.reason}
  for entry in allowed:
    if entry not in long_keys:
      failures.append("%s: allow-list entry '%s' names no long function without a reason: "
                      "remove it" % (args.allow, entry))
  for fn in long_functions:
    if fn.reason or fn.key in allowed:
      print("allowed: %s (%d lines)%s" % (fn.key, fn.length,
                                          ": " + fn.reason if fn.reason else ": allow-list"))
  for line in errors + failures:
    print(line)
  print("long_functions: %d files, %d functions over %d lines, %d not allowed, %d errors"
        % (files, len(long_functions), args.limit, len(failures), len(errors)))
  return 1 if failures or errors else 0


if __name__ == "__main__":
  sys.exit(main(sys.argv[1:]))
