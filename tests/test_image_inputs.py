"""Outside image files the audit must refuse, or read quietly: paths that are not regular
files (a named pipe, a device), damaged files whose library prints its own diagnostics, a
header that claims another size than the frame's other files, and renders too flat for the
photometric sign check to tell the two disparity signs apart."""

import json
import os
import struct
import threading
from pathlib import Path

import cv2
import numpy as np
import pytest

from stereovar.audit.importer import import_audit, import_record
from stereovar.audit.sign import CLEARLY_BETTER, MIN_PIXELS, SAME, sign_check
from stereovar.audit.synthetic import synthetic_frame, write_synthetic_audit
from stereovar.errors import AuditError, ImageError
from stereovar.io import images
from stereovar.io.headers import image_size
from stereovar.io.images import read_field, read_image
from stereovar.io.writers import write_image
from stereovar.renderers.quiet import silenced

SMALL = {"width": 64, "height": 40, "n_seeds": 4}
RNG = np.random.default_rng(11)


def finishes(call, *, unblock=(), seconds=20.0):
    """``call()``'s exception (None when it returns), failing the test if it is still running
    after ``seconds`` (a blocking open of a named pipe); the pipes in ``unblock`` are then
    opened for writing, which releases a reader blocked in its open."""
    outcome = {}

    def run():
        try:
            call()
            outcome["error"] = None
        except Exception as err:  # the outcome under test
            outcome["error"] = err

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(seconds)
    if worker.is_alive():
        for fifo in unblock:
            try:
                os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
            except OSError:
                pass
        worker.join(5.0)
        pytest.fail(f"{call} blocked for {seconds} s")
    return outcome["error"]


def claim_size(path, width, height):
    """Rewrite an EXR's data and display windows to ``width`` x ``height`` in place (the
    pixel data stays as it was)."""
    data = bytearray(path.read_bytes())
    for name in (b"dataWindow\x00box2i\x00", b"displayWindow\x00box2i\x00"):
        at = data.index(name) + len(name)
        assert struct.unpack("<i", data[at : at + 4]) == (16,)
        data[at + 4 : at + 20] = struct.pack("<4i", 0, 0, width - 1, height - 1)
    path.write_bytes(bytes(data))


@pytest.fixture
def synthetic(tmp_path, monkeypatch):
    """One synthetic frame as EXR renders and PFM disparity, in a fresh working directory."""
    monkeypatch.chdir(tmp_path)
    return write_synthetic_audit(tmp_path / "data", n_frames=1, **SMALL)


# --------------------------------------------------------------------------------------------
# paths that are not regular files
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["a named pipe", "a character device", "a directory"])
def test_a_path_that_is_not_a_regular_file_is_refused_without_opening_it(tmp_path, kind):
    path = tmp_path / "seed_000.exr"
    if kind == "a named pipe":
        os.mkfifo(path)
    elif kind == "a character device":
        os.symlink("/dev/zero", path)
    else:
        path.mkdir()
    for call in (image_size, read_image, read_field):
        error = finishes(lambda call=call: call(path), unblock=[path])
        assert isinstance(error, ImageError), error
        assert str(error) == (
            f"{path}: not a regular file ({kind}); give the path of an image file"
        )


def test_missing_file_is_still_no_such_file(tmp_path):
    with pytest.raises(ImageError, match=r"a\.exr: no such file"):
        image_size(tmp_path / "a.exr")
    os.symlink(tmp_path / "elsewhere.exr", tmp_path / "b.exr")  # a dangling link
    with pytest.raises(ImageError, match=r"b\.exr: no such file"):
        read_image(tmp_path / "b.exr")


def test_audit_with_a_named_pipe_render_or_a_device_disparity_says_so(synthetic):
    settings, _ = synthetic
    render = settings["renders"].format(frame="f00", view="R", seed="002")
    os.remove(render)
    os.mkfifo(render)
    error = finishes(lambda: import_audit(settings), unblock=[render])
    assert isinstance(error, ImageError)
    assert str(error).startswith(f"{render}: not a regular file (a named pipe)")
    os.remove(render)
    write_image(render, np.zeros((SMALL["height"], SMALL["width"], 3), np.float32))
    disparity = settings["disparity"].format(frame="f00")
    os.remove(disparity)
    os.symlink("/dev/zero", disparity)
    error = finishes(lambda: import_audit(settings))
    assert isinstance(error, ImageError)
    assert str(error).startswith(f"{disparity}: not a regular file (a character device)")
    assert not os.path.exists("results/audit/synthetic/import.json")


# --------------------------------------------------------------------------------------------
# the libraries' own diagnostics
# --------------------------------------------------------------------------------------------


def test_damaged_files_give_stereovars_line_and_nothing_else(tmp_path, capfd):
    exr, png = tmp_path / "a.exr", tmp_path / "a.png"
    write_image(exr, RNG.random((40, 64, 3)).astype(np.float32))
    write_image(png, RNG.random((40, 64, 3)).astype(np.float32))
    exr.write_bytes(exr.read_bytes()[: exr.stat().st_size // 2])
    broken = bytearray(png.read_bytes())
    broken[100] ^= 0xFF  # a CRC error inside IDAT
    png.write_bytes(bytes(broken))
    capfd.readouterr()
    for path in (exr, png):
        for call in (read_image, read_field):
            with pytest.raises(ImageError, match=rf"{path.name}: cannot read the file"):
                call(path)
    out, err = capfd.readouterr()
    assert (out, err) == ("", "")
    # both descriptors are back where they were
    os.write(1, b"out\n")
    os.write(2, b"err\n")
    assert capfd.readouterr() == ("out\n", "err\n")


def test_damaged_files_decoded_by_parallel_threads_leave_stderr_working(tmp_path, capfd):
    paths = []
    for k in range(8):
        path = tmp_path / f"seed_{k}.exr"
        write_image(path, RNG.random((40, 64, 3)).astype(np.float32))
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
        paths.append(path)
    capfd.readouterr()
    errors = []

    def decode(path):
        for _ in range(5):
            try:
                read_image(path)
            except ImageError as err:
                errors.append(err)

    threads = [threading.Thread(target=decode, args=(p,)) for p in paths]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(errors) == 5 * len(paths)
    os.write(2, b"still here\n")
    assert capfd.readouterr() == ("", "still here\n")


def test_overlapping_silenced_blocks_restore_the_descriptor(capfd):
    # A enters, B enters, A leaves, B leaves: the descriptor is silent until B leaves and
    # is the original one afterwards
    a_in, b_in, a_out = threading.Event(), threading.Event(), threading.Event()

    def first():
        with silenced(2):
            a_in.set()
            b_in.wait()
        a_out.set()

    def second():
        a_in.wait()
        with silenced(2):
            b_in.set()
            a_out.wait()
            os.write(2, b"hidden\n")

    threads = [threading.Thread(target=first), threading.Thread(target=second)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    os.write(2, b"shown\n")
    assert capfd.readouterr().err == "shown\n"


# --------------------------------------------------------------------------------------------
# a header that claims another size
# --------------------------------------------------------------------------------------------


def test_read_into_a_stack_checks_the_header_before_decoding(tmp_path, monkeypatch):
    path = tmp_path / "seed_000.exr"
    write_image(path, RNG.random((40, 64, 3)).astype(np.float32))
    claim_size(path, 100_000, 100_000)
    decoded = []
    monkeypatch.setattr(images, "_exr_rgb", lambda p: decoded.append(p))
    out = np.zeros((40, 64, 3), np.float32)
    with pytest.raises(ImageError) as raised:
        read_image(path, out=out)
    assert str(raised.value) == (
        f"{path}: its header says 100000x100000 px but the other renders are 64x40; export "
        "every render at one resolution"
    )
    assert decoded == []
    assert not out.any()


@pytest.mark.parametrize("seed", ["000", "002"])
def test_audit_names_the_file_whose_header_claims_another_size(synthetic, monkeypatch, seed):
    settings, _ = synthetic
    bad = settings["renders"].format(frame="f00", view="L", seed=seed)
    claim_size(Path(bad), 100_000, 100_000)
    decoded = []
    for name in ("_exr_rgb", "_exr_channels", "read_pfm"):
        monkeypatch.setattr(images, name, lambda p, name=name: decoded.append(name))
    with pytest.raises(AuditError) as raised:
        import_audit(settings)
    n_files = 2 * SMALL["n_seeds"] + 1  # both views' renders and the disparity
    assert str(raised.value) == (
        f"{bad} is 100000x100000 px but the frame's other {n_files - 1} files are 64x40 px; "
        "every render, disparity, depth and mask of a frame needs the same size: export them "
        "at one resolution"
    )
    assert decoded == []


# --------------------------------------------------------------------------------------------
# a sign check that cannot tell the signs apart
# --------------------------------------------------------------------------------------------


def dark_png_codes(frame, view, divisor):
    """One-channel 8-bit linear codes of a view's renders at 1/``divisor`` of full scale."""
    return [
        np.round(np.clip(r.mean(axis=-1) / divisor, 0.0, 1.0) * 255).astype(np.uint8)
        for r in frame.renders[view]
    ]


def brute_force_same(left, right, disparity, valid, sign):
    """Fraction of the left pixels compared under both signs (integer disparity: exact
    samples) whose two warped right values agree; also each sign's compared count."""
    height, width = left.shape
    same, both, counts = 0, 0, {sign: 0, -sign: 0}
    for y in range(height):
        for x in range(width):
            d = disparity[y, x]
            inside = {
                s: bool(valid[y, x]) and d > 0 and 0 <= x + s * d <= width - 1
                for s in (sign, -sign)
            }
            for s in inside:
                counts[s] += inside[s]
            if all(inside.values()):
                both += 1
                a, b = right[y, int(x + sign * d)], right[y, int(x - sign * d)]
                same += abs(a - b) <= SAME * max(left[y, x], SAME)
    return same / both, counts


def test_sign_check_whose_warps_are_identical_is_inconclusive_and_says_why():
    frame = synthetic_frame(sign=-1, **SMALL)
    means = {
        v: np.mean(dark_png_codes(frame, v, 400.0), axis=0, dtype=np.float64) / 255
        for v in ("left", "right")
    }
    valid = frame.valid
    check = sign_check(
        np.repeat(means["left"][..., None], 3, -1),
        np.repeat(means["right"][..., None], 3, -1),
        frame.disparity,
        sign=-1,
        valid=valid,
    )
    # the quantised renders are black nearly everywhere: both signs match exactly
    assert check.error == 0.0 and check.opposite_error == 0.0
    same, counts = brute_force_same(means["left"], means["right"], frame.disparity, valid, -1)
    assert (check.n_pixels, check.opposite_n_pixels) == (counts[-1], counts[1])
    assert check.same_fraction == pytest.approx(same, rel=1e-12)
    assert same > 0.9
    assert not check.conclusive and not check.opposite_wins
    assert check.reason == (
        f"the two signs' warps agree at {100 * same:.1f}% of the {check.n_pixels} compared "
        "pixels (the renders are flat there: black, saturated or flattened by quantisation), "
        "so neither sign can match better"
    )


def test_sign_check_reasons_for_few_pixels_and_for_no_clear_winner():
    rng = np.random.default_rng(2)
    left = rng.uniform(0.5, 2.0, (8, 40, 3))
    d = np.full((8, 40), 2.0)
    few = np.zeros((8, 40), bool)
    few[0, 5:15] = True
    check = sign_check(left, left, d, sign=-1, valid=few)
    assert check.n_pixels == 10 < MIN_PIXELS and not check.conclusive
    assert check.reason == f"only 10 pixels can be compared ({MIN_PIXELS} needed)"
    # unrelated right image: both signs are equally bad
    check = sign_check(left, rng.uniform(0.5, 2.0, (8, 40, 3)), d, sign=-1)
    assert not check.conclusive and check.same_fraction < 0.01
    assert check.reason.startswith(
        "neither sign matches clearly better (the declared one is closer at "
    )
    assert check.wins[1] <= 0.5 <= check.wins[2]
    # the right image is the left one moved by the declared sign: conclusive, no reason
    moved = np.roll(left, -2, axis=1)
    check = sign_check(left, moved, d, sign=-1)
    assert check.conclusive and check.error == 0.0 and check.reason == ""


def test_the_share_of_pixels_each_sign_matches_better_is_reported():
    # a smooth texture under noise: both median errors are large and close (inconclusive),
    # and the reason gives the share of pixels at which the declared sign is closer
    rng = np.random.default_rng(3)
    height, width = 64, 96
    x = np.arange(width + 8)
    texture = 1.0 + 0.5 * np.sin(x / 2.0)[None, :, None] * np.ones((height, 1, 3))
    left = texture[:, 4 : 4 + width] + rng.normal(0, 0.7, (height, width, 3))
    right = texture[:, 7 : 7 + width] + rng.normal(0, 0.7, (height, width, 3))
    d = np.full((height, width), 3.0)  # x_R = x_L - 3
    check = sign_check(left, right, d, sign=-1)
    assert check.error > CLEARLY_BETTER * check.opposite_error  # the ratio cannot tell
    assert not check.conclusive and check.wins[1] > 0.5
    # the share against a brute-force count over the pixels both warps compare
    closer = untied = 0
    for yy in range(height):
        for xx in range(3, width - 3):
            lum = left[yy, xx].mean()
            e, e_opp = abs(right[yy, xx - 3].mean() - lum), abs(right[yy, xx + 3].mean() - lum)
            closer += e < e_opp
            untied += e != e_opp
    share, low, high = check.wins
    assert share == pytest.approx(closer / untied, rel=1e-12)
    assert check.reason == (
        "neither sign matches clearly better (the declared one is closer at "
        f"{100 * share:.1f}% [{100 * low:.1f}, {100 * high:.1f}] of the pixels)"
    )


def test_dark_one_channel_8_bit_png_stops_the_import_unless_sign_check_warn(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(
        tmp_path / "d", n_frames=1, render_format="npy", **SMALL
    )
    for view, letter in (("left", "L"), ("right", "R")):
        for s, codes in enumerate(dark_png_codes(frames[0], view, 400.0)):
            npy = settings["renders"].format(frame="f00", view=letter, seed=f"{s:03d}")
            assert cv2.imwrite(npy.replace(".npy", ".png"), codes)  # (H, W) uint8: grey
            os.remove(npy)
    png = {**settings, "renders": settings["renders"].replace(".npy", ".png")}
    png.update(transfer="linear", scale=400.0)
    with pytest.raises(AuditError) as err:
        import_audit(png)
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(
        "frame f00: the sign check is inconclusive: the two signs' warps agree at "
    )
    assert "set audit.sign_check: warn to go on with convention conventional" in message
    assert not os.path.exists("results/audit/synthetic/ground_truth/f00.zarr")
    report = import_audit({**png, "sign_check": "warn"})
    sign_lines = [f for f in report.flags if f["kind"] == "sign_check"]
    assert len(sign_lines) == 1 and sign_lines[0]["frame"] == "f00"
    assert sign_lines[0]["text"].endswith(
        "so neither sign can match better (median error 0.0% declared, 0.0% opposite); "
        "audit.convention: conventional is taken as given (audit.sign_check: warn)"
    )
    record = json.loads(open(import_record("synthetic", "f00")).read())
    assert sign_lines[0] in record["found"]["warnings"]
    assert record["found"]["sign"]["conclusive"] is False
