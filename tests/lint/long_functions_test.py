#!/usr/bin/env python3
"""Tests of long_functions.py on a fixture tree (fixtures/project) and on small snippets: it must
catch a long function, accept a reason or an allow-list entry, and refuse a stale entry."""

import io
import os
import contextlib
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import long_functions  # noqa: E402

FIXTURE = os.path.join(HERE, "fixtures", "project")


def run(*args):
  out = io.StringIO()
  with contextlib.redirect_stdout(out):
    rc = long_functions.main(list(args))
  return rc, out.getvalue()


def lengths(text):
  functions, error = long_functions.scan_text(text, "x.cc")
  assert error is None, error
  return {fn.name: fn.length for fn in functions}


class FixtureTree(unittest.TestCase):
  def test_lists_every_function_over_the_limit(self):
    rc, out = run(FIXTURE, "--list")
    self.assertEqual(rc, 0)
    names = sorted(line.split()[2] for line in out.splitlines())
    self.assertEqual(names, sorted([
        "AllowListed81", "EmptyReason81", "MultiLineSignature81", "ReasonTooFar81",
        "Reasoned81", "TooLong81", "Widget::Inline81", "Widget::Widget", "WithLambdaInside",
        "kLambda82"]))
    self.assertNotIn("Exactly80", out)
    self.assertNotIn("RawString", out)

  def test_fails_on_long_functions_without_reason_and_on_stale_entries(self):
    rc, out = run(FIXTURE, "--allow", os.path.join(FIXTURE, "allow.txt"))
    self.assertEqual(rc, 1)
    failing = sorted(line.split(": ")[1].split(" is ")[0] for line in out.splitlines()
                     if line.startswith("src/sample.cc:"))
    self.assertEqual(failing, sorted([
        "EmptyReason81", "MultiLineSignature81", "ReasonTooFar81", "TooLong81",
        "Widget::Inline81", "Widget::Widget", "WithLambdaInside", "kLambda82"]))
    self.assertIn("allowed: src/sample.cc:AllowListed81 (81 lines): allow-list", out)
    self.assertIn("allowed: src/sample.cc:Reasoned81 (81 lines): a flat table reads best whole",
                  out)
    self.assertIn("allow-list entry 'src/sample.cc:fixture_never_long' names no long function",
                  out)
    # The multi-line signature is reported at its first line, the body measured from its '{'.
    self.assertRegex(out, r"src/sample.cc:(\d+): MultiLineSignature81 is 81 lines")

  def test_a_higher_limit_passes(self):
    rc, out = run(FIXTURE, "--limit", "106")
    self.assertEqual(rc, 0, out)
    rc, out = run(FIXTURE, "--limit", "105")
    self.assertEqual(rc, 1, out)
    self.assertIn("WithLambdaInside is 106 lines", out)


class Snippets(unittest.TestCase):
  def test_namespaces_classes_and_initialisers_are_not_functions(self):
    got = lengths("namespace a {\nstruct S {\n  int f() {\n    return 1;\n  }\n};\n"
                  "const int k[] = {\n1,\n2};\nenum E {\nkA,\nkB\n};\n"
                  "extern \"C\" {\nint g(int x) {\n  x++;\n  return x;\n}\n}\n}  // namespace a\n")
    self.assertEqual(got, {"S::f": 1, "g": 2})

  def test_braces_in_literals_and_comments_are_ignored(self):
    got = lengths("int f() {\n  const char* s = \"{{\";\n  char c = '}';\n  // }\n  /* { */\n"
                  "  return R\"x(})x\"[0] + s[0] + c;\n}\nint g() {\n  return 0;\n}\n")
    self.assertEqual(got, {"f": 5, "g": 1})

  def test_constructor_initialiser_list_and_operators(self):
    got = lengths("A::A(int a)\n    : a_(a),\n      b_{a} {\n  Run();\n}\n"
                  "A& A::operator+=(const A& o) {\n  a_ += o.a_;\n  return *this;\n}\n"
                  "bool operator==(const A& x, const A& y) {\n  return x.a_ == y.a_;\n}\n")
    self.assertEqual(got, {"A::A": 1, "A::operator+=": 2, "operator==": 1})

  def test_test_cases_are_named_by_their_title(self):
    got = lengths('TEST_CASE("first " "part", "[unit]") {\n  CHECK(1);\n}\n')
    self.assertEqual(got, {'TEST_CASE("first part")': 1})


if __name__ == "__main__":
  unittest.main()
