#!/usr/bin/env python3
"""scripts/house_check.py on small made-up trees: an upward include, a folder or file outside the
app's libraries, a cycle of floors, a documented name the code lacks, a source without a test."""

import atexit
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import house_check  # noqa: E402

APP_CMAKE = """# floors
irdist_app_folder(inputs SOURCES recipe.cc PUBLIC_DEPS irdist_base)
irdist_app_folder(runs SOURCES run.cc BELOW inputs PRIVATE_DEPS yaml-cpp)
irdist_app_folder(cli SOURCES cli.cc BELOW runs)
"""


class Tree:
    """A repository in a temporary folder, written file by file."""

    def __init__(self):
        self.root = tempfile.mkdtemp(prefix="house_check_test.")
        atexit.register(shutil.rmtree, self.root, True)

    def write(self, path, text=""):
        full = os.path.join(self.root, path)
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, "w", encoding="utf-8") as f:
            f.write(text)
        return self


def clean_tree():
    tree = Tree()
    tree.write("app/CMakeLists.txt", APP_CMAKE)
    tree.write("app/inputs/recipe.cc", '#include "app/inputs/recipe.h"\n#include "base/check.h"\n')
    tree.write("app/inputs/recipe.h", "#pragma once\nstruct Recipe {};\n")
    tree.write("app/runs/run.cc", '#include "app/inputs/recipe.h"\n#include "station/sweep.h"\n')
    tree.write("app/cli/cli.cc", '#include "app/runs/run.h"\n#include "app/inputs/recipe.h"\n')
    tree.write("app/cli/main.cc", '#include "app/cli/cli.h"\n')
    tree.write("base/check.h", "#pragma once\n#include <string>\n")
    tree.write("station/sweep.h", '#pragma once\n#include "base/check.h"\nvoid RunSweep();\n')
    return tree


class LayersTest(unittest.TestCase):
    def test_a_clean_tree_has_no_findings(self):
        self.assertEqual(house_check.check_layers(clean_tree().root), [])

    def test_an_include_from_a_lower_app_folder_to_a_higher_one_is_named_with_its_line(self):
        tree = clean_tree().write("app/inputs/recipe.cc", '#include "base/check.h"\n'
                                  '#include "app/runs/run.h"\n')
        findings = house_check.check_layers(tree.root)
        self.assertEqual(len(findings), 1)
        self.assertIn("app/inputs/recipe.cc:2: includes app/runs/run.h", findings[0])
        self.assertIn("app/runs is not below app/inputs", findings[0])

    def test_floors_below_are_followed_transitively(self):
        # cli lists only runs; inputs is below runs, so cli may include it.
        self.assertEqual(house_check.check_layers(clean_tree().root), [])
        tree = clean_tree().write("app/runs/run.cc", '#include "app/cli/cli.h"\n')
        self.assertIn("app/cli is not below app/runs", house_check.check_layers(tree.root)[0])

    def test_a_module_including_another_module_or_app_is_refused(self):
        tree = clean_tree().write("station/sweep.h", '#include "estimator/fit.h"\n')
        tree.write("base/check.h", '#include "station/sweep.h"\n')
        tree.write("estimator/fit.h", '#include "app/inputs/recipe.h"\n')
        findings = "\n".join(house_check.check_layers(tree.root))
        self.assertIn("station/sweep.h:1: includes estimator/fit.h", findings)
        self.assertIn("base/check.h:1: includes station/sweep.h", findings)
        self.assertIn("estimator/fit.h:1: includes app/inputs/recipe.h", findings)

    def test_a_folder_or_source_outside_the_libraries_is_named(self):
        tree = clean_tree().write("app/extra/thing.cc", "")
        tree.write("app/runs/orphan.cc", "")
        findings = "\n".join(house_check.check_layers(tree.root))
        self.assertIn("app/extra/: no library of its own", findings)
        self.assertIn("app/runs/orphan.cc: in no library", findings)

    def test_a_cycle_of_floors_is_refused(self):
        tree = clean_tree().write("app/CMakeLists.txt", APP_CMAKE.replace(
            "SOURCES recipe.cc", "SOURCES recipe.cc BELOW cli"))
        self.assertIn("form a cycle", "\n".join(house_check.check_layers(tree.root)))


class DocsTest(unittest.TestCase):
    def docs_findings(self, text):
        tree = clean_tree().write("docs/architecture.md", text)
        return house_check.check_docs(tree.root)

    def test_named_files_functions_and_folders_that_exist_pass(self):
        self.assertEqual(self.docs_findings(
            "`base/check.h`, `check.h`, `station/`, `RunSweep`, `Recipe`, `app/cli/main.cc`, "
            "`tests/<module>/<file>_test.cc`, `fuzz/corpus/TARGET`, `camera.trigger: readout`\n"
            "| `runs/` | `run` | the runs |\n| `cli/` | `cli`, `main.cc` | the top |\n"), [])

    def test_a_function_or_file_the_code_lacks_is_named_with_its_line(self):
        findings = self.docs_findings("intro\n`AppendBracket` in `app/runs/capture.cc`\n")
        self.assertEqual(len(findings), 2)
        self.assertIn("docs/architecture.md:2: `AppendBracket` names no AppendBracket", findings[0])
        self.assertIn("no file or folder app/runs/capture.cc", findings[1])

    def test_a_name_only_in_a_comment_does_not_count(self):
        tree = clean_tree().write("app/runs/run.cc", "// CommitBracket happens here\n")
        tree.write("docs/architecture.md", "`CommitBracket`\n")
        self.assertEqual(len(house_check.check_docs(tree.root)), 1)

    def test_the_app_table_names_every_file_of_its_folder(self):
        findings = self.docs_findings("| `inputs/` | `recipe` | inputs |\n| `runs/` | | runs |\n")
        self.assertEqual(findings, ["docs/architecture.md:2: app/runs/run is not in the table: "
                                    "add it with its role"])

    def test_the_app_table_names_the_folders_files(self):
        findings = self.docs_findings("| `runs/` | `run`, `capture.{h,cc}` | the runs |\n")
        table = [f for f in findings if "app/runs/ has no" in f]
        self.assertEqual(len(table), 2)
        self.assertIn("docs/architecture.md:1: app/runs/ has no capture.h", table[0])


class TestsReportTest(unittest.TestCase):
    def test_a_source_without_its_test_file_is_listed(self):
        tree = clean_tree().write("tests/app/inputs/recipe_test.cc", "")
        listed = "\n".join(house_check.check_tests(tree.root))
        self.assertNotIn("app/inputs/recipe.cc", listed)
        self.assertIn("app/runs/run.cc: no test file of its own (tests/app/runs/run_test.cc)",
                      listed)
        self.assertNotIn("main.cc", listed)


if __name__ == "__main__":
    unittest.main()
