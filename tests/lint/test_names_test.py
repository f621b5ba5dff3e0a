#!/usr/bin/env python3
"""Tests of test_names.py on its fixtures (fixtures/test_names): it must report every TEST_CASE,
TEST_CASE_METHOD, SCENARIO and SECTION name with ';' (continuation lines too), and nothing else."""

import contextlib
import io
import os
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import test_names  # noqa: E402

FIXTURES = os.path.join(HERE, "fixtures", "test_names")


def run(*args):
  out = io.StringIO()
  with contextlib.redirect_stdout(out):
    rc = test_names.main(list(args))
  return rc, out.getvalue()


class Fixtures(unittest.TestCase):
  def test_fires_on_every_name_with_a_semicolon(self):
    rc, out = run(os.path.join(FIXTURES, "bad_names.cc"))
    self.assertEqual(rc, 1)
    reported = [line.split(": ", 1)[1].split(" has ';'")[0] for line in out.splitlines()
                if " has ';'" in line]
    self.assertEqual(reported, [
        'TEST_CASE("one line; with a semicolon")',
        'TEST_CASE("a name continued on the next line, the semicolon there; still found")',
        'SECTION("a section; also split")',
        'TEST_CASE_METHOD("a fixture test; named after the fixture")',
        'SCENARIO("a scenario; too")'])
    self.assertIn("bad_names.cc:6: TEST_CASE(", out)  # reported at the macro's line
    self.assertIn("test_names: 7 names, 5 with ';'", out)

  def test_passes_clean_names(self):
    rc, out = run(os.path.join(FIXTURES, "good_names.cc"))
    self.assertEqual(rc, 0, out)
    self.assertIn("test_names: 2 names, 0 with ';'", out)

  def test_a_folder_scan_skips_the_fixtures(self):
    rc, out = run(HERE)
    self.assertEqual(rc, 0, out)
    self.assertNotIn("bad_names.cc", out)

  def test_bad_use(self):
    self.assertEqual(run()[0], 2)
    self.assertEqual(run(os.path.join(FIXTURES, "missing"))[0], 2)


if __name__ == "__main__":
  unittest.main()
