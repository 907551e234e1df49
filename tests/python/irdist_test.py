"""Tests of the Python module irdist (python/): a smoke calibration's recording read into numpy
(fixture python/smoke_run), a bracket estimated from it against the station's truth and against
`irdist playback` (the same numbers as measure's JSON), and the live measure() iterator stopped by
closing it."""
import csv
import math
import os
import re
import subprocess
import tempfile
import unittest
import warnings

import numpy as np

import irdist

RUN = os.environ["IRDIST_SMOKE_RUN"]
RECORDING = os.path.join(RUN, "recording")
MODEL = os.path.join(RUN, "model.yaml")


class RecordingTest(unittest.TestCase):
    def setUp(self):
        self.rec = irdist.Recording(RECORDING)

    def test_frames_are_uint16_arrays_with_their_frames_csv_row(self):
        with open(os.path.join(RECORDING, "frames.csv"), newline="") as f:
            table = list(csv.DictReader(f))
        self.assertEqual(len(self.rec), len(table))
        image, row = self.rec[3]
        self.assertEqual(image.dtype, np.uint16)
        self.assertEqual(image.ndim, 2)
        self.assertEqual(set(row), set(table[0]), "every frames.csv column, no other")
        self.assertEqual(row["index"], 3)
        self.assertIsInstance(row["bracket_id"], int)
        self.assertIsInstance(row["requested_exposure_us"], float)
        self.assertIn(row["role"], ("ref", "meas"))
        self.assertEqual(row["slide_mm"], float(table[3]["slide_mm"]))
        self.assertEqual(row["utc_time"], table[3]["utc_time"])
        self.assertEqual(row["host_monotonic_ns"], int(table[3]["host_monotonic_ns"]))
        self.assertRegex(row["utc_time"], r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{6}Z$")
        self.assertEqual(irdist.format_utc(row["host_time_ns"]), row["utc_time"])
        # The pixels are the PNG's, and the array does not own them (no copy of the frame).
        self.assertFalse(image.flags.owndata)
        self.assertGreater(int(image.max()), 0)
        self.assertEqual(int(self.rec[-1][1]["index"]), len(self.rec) - 1)
        with self.assertRaises(IndexError):
            self.rec[len(self.rec)]

    def test_iteration_and_brackets_cover_every_frame_once(self):
        indices = [row["index"] for _, row in self.rec]
        self.assertEqual(indices, list(range(len(self.rec))))
        brackets = list(self.rec.brackets())
        self.assertEqual(sum(len(rows) for _, rows in brackets), len(self.rec))
        for images, rows in brackets:
            self.assertEqual(len(images), len(rows))
            self.assertEqual(len({r["bracket_id"] for r in rows}), 1)
            self.assertEqual([r["frame_in_bracket"] for r in rows], list(range(len(rows))))
        self.assertEqual(self.rec.header["completion"], "complete")
        self.assertEqual(self.rec.header["command"], "calibrate")
        self.assertEqual(self.rec.header["unverified_rows"], 0)

    def test_a_damaged_recording_is_refused_with_its_file_and_line(self):
        with tempfile.TemporaryDirectory() as tmp:
            copy = os.path.join(tmp, "recording")
            subprocess.run(["cp", "-r", RECORDING, copy], check=True)
            os.remove(os.path.join(copy, "frames", "000002.png"))
            with self.assertRaisesRegex(irdist.RecordingError, "000002.png"):
                irdist.Recording(copy)

    def test_bad_indices_raise_index_error_with_a_message_and_a_nul_path_is_refused(self):
        n = len(self.rec)
        for bad in (10**20, -10**20, n, -n - 1):
            with self.assertRaisesRegex(IndexError, "out of range: the recording has %d rows" % n):
                self.rec[bad]
        for bad in (-1, n, 10**20):
            with self.assertRaisesRegex(IndexError, r"no frame %d in .*indices 0\.\.%d" % (bad, n - 1)):
                self.rec.image(bad)
        with self.assertRaises(TypeError):
            self.rec["3"]
        self.assertEqual(self.rec[np.int64(3)][1]["index"], 3)
        self.assertEqual(self.rec.image(n - 1).shape, self.rec[-1][0].shape)
        with self.assertRaisesRegex(ValueError, "NUL character"):
            irdist.Recording(RECORDING + "\0junk")

    def test_a_recording_being_written_is_named_with_its_writer(self):
        import fcntl
        with tempfile.TemporaryDirectory() as tmp:
            copy = os.path.join(tmp, "recording")
            subprocess.run(["cp", "-r", RECORDING, copy], check=True)
            with open(os.path.join(copy, "writer.lock"), "w") as lock:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                lock.write("%d\n" % os.getpid())
                lock.flush()
                with self.assertRaisesRegex(irdist.RecordingError,
                                            "being written by process %d" % os.getpid()):
                    irdist.Recording(copy)
                with self.assertWarnsRegex(UserWarning,
                                           "being written by process %d" % os.getpid()):
                    live = irdist.Recording(copy, check=False)
                self.assertEqual(len(live), len(self.rec))
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # no warning once the writer is gone
                self.assertEqual(len(irdist.Recording(copy, check=False)), len(self.rec))
            self.assertEqual(len(irdist.Recording(copy)), len(self.rec))


def playback_rows(out_dir):
    """The i0_free joint rows (dt_ms 0) of `irdist playback` on the recording, by bracket."""
    subprocess.run([irdist.executable(), "playback", RECORDING, "--model", MODEL, "--out", out_dir],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out_dir, "estimates.csv"), newline="") as f:
        return {int(r["bracket"]): r for r in csv.DictReader(f)
                if r["method"] == "i0_free" and float(r["dt_ms"]) == 0.0}


class ModelTest(unittest.TestCase):
    def test_a_bracket_is_estimated_within_one_percent_of_the_truth_as_playback_does(self):
        model = irdist.Model(MODEL)
        rec = irdist.Recording(RECORDING)
        with tempfile.TemporaryDirectory() as tmp:
            playback = playback_rows(os.path.join(tmp, "playback"))
        checked = 0
        for images, rows in list(rec.brackets())[::5]:
            m = model.estimate_bracket(images, [r["requested_exposure_us"] for r in rows],
                                       roles=[r["role"] for r in rows])
            self.assertEqual(m["schema"], irdist.MEASURE_JSON_SCHEMA)
            self.assertTrue(m["ok"], m)
            truth_mm = rows[0]["slide_mm"]
            self.assertLess(abs(m["d_mm"] - truth_mm), 0.01 * truth_mm, m)
            expected = playback[rows[0]["bracket_id"]]
            self.assertAlmostEqual(m["d_mm"], float(expected["d_mm"]), delta=0.01)
            self.assertAlmostEqual(m["theta_deg"], float(expected["theta_deg"]), delta=0.001)
            # The same flags as estimates.csv's column: name=figure, notes leave it trusted.
            causes = " ".join(c["name"] + ("=" + c["figure"] if c["figure"] else "")
                              for c in m["causes"])
            self.assertEqual(causes, expected["flags"], m)
            self.assertEqual(m["trusted"], not any(c["suspect"] for c in m["causes"]), m)
            self.assertAlmostEqual(m["d_se_mm"], float(expected["d_se_mm"]), delta=1e-3)
            # The focus as calibrated: measured with the calibrated blur, not refocused.
            self.assertFalse(m["flags"]["refocused"], m)
            self.assertEqual(m["health"]["figure"], "blob_fit", m)
            checked += 1
        self.assertGreaterEqual(checked, 4)

    def test_features_of_a_frame(self):
        model = irdist.Model(MODEL)
        image, _ = irdist.Recording(RECORDING)[1]
        f = model.features(image)
        self.assertTrue(f["blob_found"])
        x, y, w, h = f["roi"]
        cx, cy = f["centroid_px"]
        self.assertTrue(x <= cx <= x + w and y <= cy <= y + h, f)
        # The blob fit's own blur, fitted with the size: the calibrated one it was given, within
        # its noise and the calibration's (the rig as calibrated).
        self.assertGreater(f["own_blur_se_px2"], 0.0, f)
        self.assertLess(abs(f["own_blur_var_px2"] / f["size_blur_var_px2"] - 1.0), 0.15, f)
        # Another dtype is converted (the same gray levels as uint16).
        self.assertEqual(model.features(image.astype(np.int32))["centroid_px"], f["centroid_px"])
        with self.assertRaises(ValueError):
            model.features(np.zeros(5, dtype=np.uint16))

    def test_bad_bit_depths_and_tiny_images_are_refused_with_a_message(self):
        # Regression: bit_depth=99 and a 1x1 image were internal check failures.
        model = irdist.Model(MODEL)
        image, _ = irdist.Recording(RECORDING)[1]
        for bits in (99, 7, -12):
            with self.assertRaisesRegex(ValueError, r"bit_depth = -?\d+ is outside \[8, 16\] bit"):
                model.features(image, bit_depth=bits)
        with self.assertRaisesRegex(ValueError, r"1 x 1 px, smaller than the model's window"):
            model.features(np.zeros((1, 1), dtype=np.uint16))
        with self.assertRaisesRegex(ValueError, r"smaller than the model's window"):
            model.estimate_bracket([image, np.zeros((1, 1), dtype=np.uint16)], [8000, 30000])


def child_pids():
    """This process's children (running or not yet reaped)."""
    pid = os.getpid()
    children = set()
    for task in os.listdir(f"/proc/{pid}/task"):
        with open(f"/proc/{pid}/task/{task}/children") as f:
            children.update(int(p) for p in f.read().split())
    return children


class MeasureTest(unittest.TestCase):
    def test_count_brackets_then_the_iterator_ends(self):
        lines = list(irdist.measure(MODEL, rig="virtual", count=2, args=["--time-scale", "10"],
                                    stderr=subprocess.DEVNULL))
        self.assertEqual([m["bracket"] for m in lines], [0, 1])
        self.assertEqual(lines[0]["schema"], irdist.MEASURE_JSON_SCHEMA)

    def test_arguments_outside_their_bounds_are_refused_before_measure_starts(self):
        # Regression: duration_s NaN passed (a measure that never ends).
        before = child_pids()
        for kwargs in ({"duration_s": float("nan")}, {"duration_s": 0}, {"duration_s": 1e9},
                       {"count": 0}):
            with self.assertRaisesRegex(ValueError, r"is outside"):
                irdist.measure(MODEL, rig="virtual", **kwargs)
        self.assertEqual(child_pids() - before, set(), "no measure was started")

    def test_closing_the_iterator_stops_measure_and_waits_for_it(self):
        before = child_pids()
        live = irdist.measure(irdist.Model(MODEL), rig="virtual", args=["--time-scale", "10"],
                              stderr=subprocess.DEVNULL)
        first = next(live)
        self.assertIn("d_mm", first)
        self.assertEqual(len(child_pids() - before), 1, "measure runs while iterated")
        live.close()
        self.assertEqual(child_pids() - before, set(), "measure ended and was reaped")

    def test_track_yields_a_dict_per_frame_in_mode_track(self):
        # irdist.measure(..., track=True), the IRED placed at 2000 mm.
        lines = list(irdist.measure(MODEL, rig="virtual", count=6, track=True,
                                    args=["--time-scale", "10", "--at", "2000,0,0,500"],
                                    stderr=subprocess.DEVNULL))
        self.assertEqual(len(lines), 6)
        self.assertEqual({m["mode"] for m in lines}, {"track"})
        self.assertEqual(lines[0]["schema"], irdist.MEASURE_JSON_SCHEMA)
        frames = [m["frame"] for m in lines]
        self.assertEqual(frames, sorted(set(frames)), "frames in order, none twice")
        # Every frame between two lines is one the estimator skipped, and counted so.
        last = lines[-1]["counters"]
        self.assertEqual(frames[-1] - frames[0] - (len(frames) - 1),
                         last["skipped"] - lines[0]["counters"]["skipped"])
        for m in lines:
            self.assertTrue(m["ok"], m)
            self.assertAlmostEqual(m["d_mm"], 2000.0, delta=0.02 * 2000.0)
            self.assertIsNotNone(m["track"])


if __name__ == "__main__":
    unittest.main(verbosity=2)
