"""CTest fixture of tests/python/: a fresh smoke calibration on the virtual rig (a recording and
its model.yaml), made once for the tests that read it.

    smoke_run.py IRDIST_PROGRAM RECIPE RUN_DIR
"""
import shutil
import subprocess
import sys

program, recipe, run_dir = sys.argv[1:4]
shutil.rmtree(run_dir, ignore_errors=True)
argv = [program, "calibrate", recipe, "--time-scale", "10", "--quiet", "--out", run_dir]
sys.exit(subprocess.run(argv, check=False).returncode)
