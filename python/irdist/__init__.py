"""irdist from Python: recordings, calibration models and live measurement (docs/python.md).

    import irdist
    rec = irdist.Recording("runs/table3-calibration-.../recording")
    image, row = rec[0]                       # numpy uint16 array, frames.csv's row as a dict
    model = irdist.Model("runs/table3-calibration-.../model.yaml")
    for images, rows in rec.brackets():
        print(model.estimate_bracket(images, [r["requested_exposure_us"] for r in rows],
                                     roles=[r["role"] for r in rows])["d_mm"])
    for m in irdist.measure(model, rig="virtual", count=10):   # irdist measure --json, live
        print(m["d_mm"])
"""

import json
import os
import shutil
import subprocess

from . import _irdist
from ._irdist import Error, ModelFileError, RecordingError, format_utc, MEASURE_JSON_SCHEMA

__all__ = ["Recording", "Model", "measure", "executable", "Error", "RecordingError",
           "ModelFileError", "format_utc", "MEASURE_JSON_SCHEMA"]


class Recording(_irdist.Recording):
    """A recording (docs/recording-format.md) read with irdist's own reader.

    Recording(path, check=True): `check` runs the checks of `irdist check` first (every PNG
    decoded) and raises RecordingError listing the errors by file and line. A recording a live run
    is writing raises with check=True; with check=False it opens with a UserWarning "being written
    by process N".
    len(rec), rec[i] and iteration give (image, row) pairs: image a numpy uint16 array (rows x
    columns, values as the camera delivered them), row frames.csv's columns as a dict.
    rec.rows: every row (no images), e.g. pandas.DataFrame(rec.rows); rec.header: recording.yaml.
    """

    def __iter__(self):
        for i in range(len(self)):
            yield self[i]

    def brackets(self, complete_only=True):
        """Yields (images, rows) per bracket, in recording order, the images loaded bracket by
        bracket. A resumed run's re-acquired bracket appears once (its last complete set)."""
        for rows in self._bracket_rows(complete_only):
            yield [self.image(row["index"]) for row in rows], rows


class Model(_irdist.Model):
    """A calibration (model.yaml). Model(path, rig=None): with a rig (name or file) that has
    camera.intrinsics, estimates carry the 3D position as measure's do.

    features(image, bit_depth=0): the frame's features (estimator/features.h) as a dict.
    estimate_bracket(images, exposures_us, bit_depth=0, roles=None): the bracket's estimate as the
    same dict as one line of `irdist measure --json` (time_s and latency_ms are None). roles:
    'ref'/'meas' per image (default: the first the reference). bit_depth 0: the model's camera's.
    """


def executable():
    """The irdist program measure() runs: $IRDIST_EXECUTABLE, else the one this module was built
    or installed with, else irdist on PATH."""
    given = os.environ.get("IRDIST_EXECUTABLE")
    if given:
        return given
    try:
        from ._location import EXECUTABLE
        if os.access(EXECUTABLE, os.X_OK):
            return EXECUTABLE
    except ImportError:
        pass
    found = shutil.which("irdist")
    if found is None:
        raise Error("irdist: no irdist program found; set IRDIST_EXECUTABLE to its path")
    return found


def measure(model, rig=None, count=None, duration_s=None, args=(), stderr=None, track=False):
    """Yields the live JSON objects of `irdist measure --json` (docs/measure.md), one dict per
    bracket, as they come. model: a Model or a model.yaml path; rig: a rig name or file; count /
    duration_s: stop after so many brackets / seconds (default: until the iterator is closed);
    args: further measure flags, e.g. ["--at", "2000,10,0,500"]. stderr: where measure's messages
    and summary go (default: this process's stderr). track=True: `measure --track`, one dict per
    frame (mode "track"; count counts frames) and per interleaved bracket (mode "bracket", with
    args ["--check-every", "S"]), docs/measure.md "Tracking".

    Closing the iterator (a `break` out of a for loop, .close(), or its garbage collection) stops
    measure as Ctrl-C does: SIGTERM, then it finishes the bracket in flight, stops the camera and
    exits; the child is always waited for. Raises Error when measure fails on its own, and
    ValueError at once for a count or duration_s outside its bound (NaN, 0, more than a day).
    """
    if count is not None:
        _irdist._check_argument("count", count)
    if duration_s is not None:
        _irdist._check_argument("duration_s", duration_s)  # NaN would never end
    path = model.path if isinstance(model, _irdist.Model) else os.fspath(model)
    argv = [executable(), "measure", "--model", path, "--json"] + (["--track"] if track else [])
    if rig is not None:
        argv += ["--rig", os.fspath(rig)]
    if count is not None:
        argv += ["--count", str(int(count))]
    if duration_s is not None:
        argv += ["--duration", str(float(duration_s))]
    argv += [str(a) for a in args]
    return _measure_lines(argv, stderr)  # the arguments above are checked before any child runs


def _measure_lines(argv, stderr):
    """The generator behind measure(): the child's JSON lines, the child stopped at the end."""
    child = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=stderr, text=True)
    stopped = False
    try:
        for line in child.stdout:
            if line.strip():
                yield json.loads(line)
    except GeneratorExit:
        stopped = True
        raise
    finally:
        _stop(child)
    if not stopped and child.returncode != 0:
        raise Error(f"irdist measure exited with status {child.returncode}: {' '.join(argv)}")


def _stop(child, wait_s=30.0):
    """Ends `child` the way Ctrl-C does and waits for it (SIGKILL only if it does not exit)."""
    if child.poll() is None:
        child.terminate()
    # Nobody reads on: a line measure is still writing ends in EPIPE, never a full pipe's wait.
    child.stdout.close()
    try:
        child.wait(timeout=wait_s)
    except subprocess.TimeoutExpired:
        child.kill()
        child.wait()
