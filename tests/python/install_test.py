"""Test of the install (cmake/IrdistInstall.cmake and `./irdist install`): into a fresh prefix,
then, from a folder outside the source tree, P/bin/irdist plans a recipe whose rig is found in
P/share/irdist (directly and through a symlink on PATH), the ./irdist launcher works through a
symlink, an install through a linked folder is refused, and a python3 with only P's site-packages added reads the smoke calibration's recording
into numpy and estimates a bracket within 1% of its truth."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

SOURCE = os.environ["IRDIST_SOURCE_DIR"]
RUN = os.environ["IRDIST_SMOKE_RUN"]


def run(argv, cwd, env=None):
    done = subprocess.run(argv, cwd=cwd, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, check=False)
    return done.returncode, done.stdout


class InstallTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="irdist_install_")
        cls.prefix = os.path.join(cls.tmp, "p")
        code, out = run([os.path.join(SOURCE, "irdist"), "install", "--prefix", cls.prefix],
                        cwd=cls.tmp)
        assert code == 0, out
        cls.install_log = out
        # A folder with a recipe and nothing else: `rig: virtual` must come from P/share/irdist.
        cls.elsewhere = os.path.join(cls.tmp, "elsewhere")
        os.makedirs(cls.elsewhere)
        shutil.copy(os.path.join(SOURCE, "recipes", "table3-calibration.yaml"), cls.elsewhere)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def env_without_the_build(self, **extra):
        env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "IRDIST_"))}
        env.update(extra)
        return env

    def test_installed_program_plans_with_the_rig_from_its_share_folder(self):
        program = os.path.join(self.prefix, "bin", "irdist")
        code, out = run([program, "plan", "table3-calibration.yaml"], cwd=self.elsewhere,
                        env=self.env_without_the_build())
        self.assertEqual(code, 0, out)
        rig = os.path.join(self.prefix, "share", "irdist", "recipes", "rigs", "virtual.yaml")
        self.assertIn(f"({rig})", out)
        for doc in ("README.md", "recording-format.md", "python.md"):
            self.assertTrue(os.path.isfile(os.path.join(self.prefix, "share", "doc", "irdist", doc)),
                            doc)

    def test_a_symlink_on_path_to_the_program_or_to_the_launcher_works(self):
        bin_dir = os.path.join(self.tmp, "path-bin")
        os.makedirs(bin_dir, exist_ok=True)
        link = os.path.join(bin_dir, "irdist")
        for target in (os.path.join(self.prefix, "bin", "irdist"), os.path.join(SOURCE, "irdist")):
            if os.path.lexists(link):
                os.remove(link)
            os.symlink(target, link)
            env = self.env_without_the_build(PATH=bin_dir + os.pathsep + os.environ["PATH"])
            if target.startswith(SOURCE):  # the launcher builds into the tests' build folder
                env["IRDIST_BUILD_DIR"] = os.environ["IRDIST_BUILD_DIR"]
            code, out = run(["irdist", "plan", "table3-calibration.yaml"], cwd=self.elsewhere,
                            env=env)
            self.assertEqual(code, 0, f"through a link to {target}:\n{out}")
            self.assertIn("rigs/virtual.yaml", out)

    def test_python_with_the_prefix_on_its_path_estimates_a_bracket(self):
        site = [os.path.join(root) for root, dirs, _ in os.walk(self.prefix) if "irdist" in dirs
                and os.path.isfile(os.path.join(root, "irdist", "__init__.py"))]
        self.assertEqual(len(site), 1, site)
        self.assertIn(f"PYTHONPATH={site[0]}", self.install_log)
        script = f"""
import irdist, numpy
assert irdist.__file__.startswith({self.prefix!r}), irdist.__file__
assert irdist.executable() == {os.path.join(self.prefix, "bin", "irdist")!r}, irdist.executable()
rec = irdist.Recording({os.path.join(RUN, "recording")!r})
model = irdist.Model({os.path.join(RUN, "model.yaml")!r})
images, rows = next(iter(rec.brackets()))
assert all(isinstance(i, numpy.ndarray) and i.dtype == numpy.uint16 for i in images)
m = model.estimate_bracket(images, [r["requested_exposure_us"] for r in rows],
                           roles=[r["role"] for r in rows])
truth = rows[0]["slide_mm"]
print("estimate", m["d_mm"], "truth", truth)
assert abs(m["d_mm"] - truth) < 0.01 * truth, m
"""
        code, out = run([sys.executable, "-c", script], cwd=self.elsewhere,
                        env=self.env_without_the_build(PYTHONPATH=site[0]))
        self.assertEqual(code, 0, out)


class InstallThroughALinkTest(unittest.TestCase):
    """Regression: `./irdist install` wrote the recipes through a linked share/irdist/recipes. A link
    anywhere the install writes stops it before the first write, naming the link."""

    def test_a_linked_recipes_folder_is_refused_and_nothing_written_through_it(self):
        with tempfile.TemporaryDirectory(prefix="irdist_install_link_") as tmp:
            prefix = os.path.join(tmp, "p")
            elsewhere = os.path.join(tmp, "elsewhere")
            os.makedirs(os.path.join(prefix, "share", "irdist"))
            os.makedirs(elsewhere)
            link = os.path.join(prefix, "share", "irdist", "recipes")
            os.symlink(elsewhere, link)
            code, out = run([os.path.join(SOURCE, "irdist"), "install", "--prefix", prefix],
                            cwd=tmp)
            self.assertNotEqual(code, 0, out)
            self.assertIn(f"{link} is a symbolic link", " ".join(out.split()))  # CMake wraps
            self.assertEqual(os.listdir(elsewhere), [], "written through the link")
            self.assertFalse(os.path.exists(os.path.join(prefix, "bin", "irdist")), out)


if __name__ == "__main__":
    unittest.main(verbosity=2)
