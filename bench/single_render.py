"""Measurement: can ONE render per view stand in for Eq. 1's N renders?

For each single-render candidate of :mod:`stereovar.estimators.single` (applied to one render
per view, repeated over the N renders to get its spread), on the default experiment's renders
(``results/mitsuba/renders/{scene}/{view}/spp{spp}/``, N = 8 per view):

1. **Agreement** with the N-seed truth (Eq. 1 over the N renders):
   the Spearman correlation of the single-render field with the Eq. 1 field of the OTHER
   N - 1 renders (left and right view averaged), and the single-render intensity-controlled
   rho (``partial``, through :func:`stereovar.statistics.registry.evaluate` with its block
   bootstrap) against the N-seed partial rho, per scene and pooled
   (:func:`stereovar.statistics.across.combined_interval`).
2. **The matched control**: each partial rho minus the same statistic on camera-law noise
   drawn on the seed mean (one frame per view, the renders' channel correlation) and
   processed by the same estimator, with
   :func:`stereovar.calibration.nulls.difference_interval` (the misaligned null's spread as
   chance).
3. **Calibration** with N = 1 per view: the false-positive rate on the matched nulls
   (``camera``, ``misaligned``) and the smallest planted strength detected with 80% power
   (a multiple of the strength the renders show, :func:`stereovar.calibration.replicates.
   render_strength`), by :func:`stereovar.calibration.summary.calibration_table`; Eq. 1 at
   N = 2 and N = 8 through the same designs as references.

4. **The null a one-render audit can build**: the two steps above draw the matched null
   on the seed mean, which one render per view does not have. The same checks are repeated
   with the null built from the single render alone
   (:func:`stereovar.estimators.single.one_render_null`: camera-law noise on the render's
   OIDN-denoised image, the law fitted to the single-render field), for the candidates
   that pass step 3's false-positive rate (``--own-methods``).

Usage::

    .venv/bin/python bench/single_render.py                      # 12 and 6 replicates
    .venv/bin/python bench/single_render.py --replicates 4 --scenes scene_000
    .venv/bin/python bench/single_render.py --out bench/single_render_output.md \
        --rows /tmp/single_render_rows.csv

981 s (16 min) on 2 cores shared with other jobs at the defaults, 1372 s under heavier load
(OIDN and the one-render null dominate: 0.3 s per 320x180 frame and view).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from stereovar.calibration.law import camera_residual_variance, render_strength  # noqa: E402
from stereovar.calibration.nulls import difference_interval  # noqa: E402
from stereovar.calibration.rates import detectable, rate  # noqa: E402
from stereovar.calibration.scene_frames import SceneFrames  # noqa: E402
from stereovar.calibration.summary import calibration_table  # noqa: E402
from stereovar.calibration.synthesis import (  # noqa: E402
    camera_law,
    draw_frames,
    planted_pattern,
    variance_fields,
)
from stereovar.estimators.seeds import variance_field  # noqa: E402
from stereovar.estimators.single import (  # noqa: E402
    METHODS,
    SingleField,
    box_mean,
    denoised,
    local_mad_variance,
    one_render_null,
    poisson_gaussian_variance,
    residual_variance,
    single_render_statistics,
)
from stereovar.probe.experiment import channel_correlation  # noqa: E402
from stereovar.seeding import derive_seed  # noqa: E402
from stereovar.statistics.across import combined_interval  # noqa: E402
from stereovar.statistics.fields import AnalysisSettings  # noqa: E402

VIEWS = ("left", "right")
SEED_PATHS = ("seeds_n2", "seeds_n8")
"""Eq. 1 references through the same designs: N = 2 (the audit's minimum) and N = 8."""


def load_scene(scene: str, *, spp: int, root: Path) -> dict:
    """The renders (N, H, W, 3) per view, the auxiliary passes, the ground truth and the
    :class:`SceneFrames` (seed mean and Eq. 1 over all N) of one scene."""
    import xarray as xr

    renders, aux = {}, {}
    for view in VIEWS:
        stores = sorted((root / "renders" / scene / view / f"spp{spp}").glob("seeds*.zarr"))
        if not stores:
            sys.exit(f"no render stores under {root}/renders/{scene}/{view}/spp{spp}; "
                     "run `snakemake -j2 all` first")
        stack = [xr.open_zarr(s)["radiance"].transpose("seed", "y", "x", "channel").values
                 for s in stores]
        renders[view] = np.concatenate(stack).astype(np.float64)
        a = xr.open_zarr(root / "renders" / scene / view / "aux.zarr").load()
        aux[view] = {k: a[k].transpose("y", "x", "channel").values for k in ("albedo", "normal")}
    g = xr.open_zarr(root.parent / "ground_truth" / f"{scene}.zarr").load()
    truth = {
        v: {"disparity": g["disparity"].sel(view=v).values,
            "valid": g["valid"].sel(view=v).values.astype(bool)}
        for v in VIEWS
    }
    mean, variance = {}, {}
    for view in VIEWS:
        mean[view], variance[view] = variance_field(renders[view])
    frames = SceneFrames(
        mean=mean, variance=variance, ground_truth=truth,
        glass=g["glass"].sel(view="left").values.astype(bool),
        sign=int(g.attrs["disparity_sign"]), n_seeds=renders["left"].shape[0],
        label=f"{scene}|spp{spp}", aux=aux,
    )
    return {"scene": scene, "renders": renders, "aux": aux, "frames": frames,
            "rho_channels": channel_correlation(renders["left"], truth["left"]["valid"])}


def candidate_fields(frames: dict, aux: dict, methods) -> dict:
    """Every candidate's :class:`SingleField` per view for one frame per view (the denoiser
    and the wavelet subband computed once and shared)."""
    out = {m: {} for m in methods}
    for view in VIEWS:
        image = frames[view]
        mean = box_mean(image)
        mad = local_mad_variance(image) if {"wavelet_mad", "poisson_gaussian"} & set(methods) \
            else None
        for m in methods:
            if m in ("oidn", "oidn_aux"):
                passes = aux[view] if m == "oidn_aux" else {}
                clean = denoised(image, **passes)
                out[m][view] = SingleField(clean, residual_variance(image, clean))
            elif m == "wavelet_mad":
                out[m][view] = SingleField(mean, mad)
            else:
                out[m][view] = SingleField(
                    mean, poisson_gaussian_variance(image, mean.mean(axis=-1))
                )
    return out


def partial_of(fields: dict, frames: SceneFrames, settings, label: str) -> dict:
    return single_render_statistics(
        fields, frames.ground_truth["left"], sign=frames.sign, settings=settings, label=label
    )["partial"]


def seed_fields(stack: dict) -> dict:
    out = {}
    for view in VIEWS:
        m, v = variance_field(np.asarray(stack[view]))
        out[view] = SingleField(m, v)
    return out


def agreement(scene: dict, methods, settings) -> list[dict]:
    """Per candidate and render n: Spearman with the leave-one-out Eq. 1 field and the
    partial rho with its bootstrap interval; the N-seed partial rho as ``seeds_n8``."""
    from scipy.stats import spearmanr

    frames, renders = scene["frames"], scene["renders"]
    n = renders["left"].shape[0]
    rows = []
    truth = partial_of(seed_fields(renders), frames, settings, f"{scene['scene']}|truth")
    rows.append({"path": "seeds_n8", "render": -1, "spearman": 1.0, **_ci(truth)})
    for k in range(n):
        one = {v: renders[v][k] for v in VIEWS}
        fields = candidate_fields(one, scene["aux"], methods)
        loo = {v: variance_field(np.delete(renders[v], k, axis=0))[1] for v in VIEWS}
        for m in methods:
            sp = np.mean([
                spearmanr(fields[m][v].variance[frames.ground_truth[v]["valid"]],
                          loo[v][frames.ground_truth[v]["valid"]]).statistic
                for v in VIEWS
            ])
            r = partial_of(fields[m], frames, settings, f"{scene['scene']}|{m}|{k}")
            rows.append({"path": m, "render": k, "spearman": float(sp), **_ci(r)})
    return rows


def _ci(result: dict) -> dict:
    return {"rho": result["rho"], "boot_low": result["boot_low"],
            "boot_high": result["boot_high"]}


def calibration_rows(scene: dict, methods, settings, *, replicates: int, factors,
                     seed: int = 0) -> tuple[list[dict], float]:
    """Replicate rows (``CALIBRATION_COLUMNS`` with ``transform`` = the estimator path) of
    the matched nulls and the planted cue, one frame per view for the candidates and N
    frames for the Eq. 1 references."""
    frames = scene["frames"]
    mu = {v: frames.mean[v].mean(axis=-1) for v in VIEWS}
    law = camera_law(frames.variance["left"], mu["left"], frames.ground_truth["left"]["valid"])
    rng0 = np.random.default_rng(derive_seed("single-render", seed, frames.label))
    render_s = max(render_strength(frames, settings,
                                   camera_residual_variance(frames, law, rng0)), 0.05)
    designs = [("camera", 0.0, 0.0), ("misaligned", 0.0, 0.0)]
    designs += [("planted", f * render_s, f) for f in factors]
    rows = []
    rho_c = scene["rho_channels"]
    for r in range(replicates):
        rng = np.random.default_rng(derive_seed("single-render", seed, frames.label, r))
        gt_r = frames.ground_truth["right"]
        pattern = planted_pattern(gt_r["disparity"], gt_r["valid"], sign=frames.sign, rng=rng)
        for kind, strength, factor in designs:
            v = variance_fields(kind, strength, mean=frames.mean, law=law,
                                render_variance=frames.variance, pattern=pattern, rng=rng)
            stack = {view: draw_frames(frames.mean[view], v[view], 8, rng,
                                       channel_correlation=rho_c).astype(np.float64)
                     for view in VIEWS}
            paths = {p: seed_fields({view: stack[view][:n] for view in VIEWS})
                     for p, n in (("seeds_n2", 2), ("seeds_n8", 8))}
            paths.update(candidate_fields({view: stack[view][0] for view in VIEWS},
                                          frames.aux, methods))
            for path, fields in paths.items():
                res = partial_of(fields, frames, settings,
                                 f"{frames.label}|{r}|{kind}|{factor:g}|{path}")
                rows.append({"scene": scene["scene"], "replicate": r, "kind": kind,
                             "strength": strength, "strength_factor": factor,
                             "transform": path, "region": "all", "method": "partial",
                             "n_pixels": 0, **_ci(res)})
    return rows, render_s


def own_difference(images: dict, aux: dict, frames: SceneFrames, method: str, settings, *,
                   rng, draws: int, label: str) -> tuple[float, float, float]:
    """One view pair's single-render partial rho minus the null built from it alone."""
    clean = {v: denoised(images[v], **aux[v]) for v in VIEWS}
    fields = {v: single_render_field_cached(images[v], method, clean[v], aux[v]) for v in VIEWS}
    observed = partial_of(fields, frames, settings, f"{label}|observed")
    null = one_render_null(images, clean, frames.ground_truth, sign=frames.sign,
                           settings=settings, rng=rng, method=method, draws=draws,
                           label=label, aux=aux)
    return difference_interval(observed["rho"], observed["boot_low"], observed["boot_high"],
                               null["null_rho"], null["null_se"], null["chance_sd"])


def single_render_field_cached(image, method, clean, passes):
    from stereovar.estimators.single import single_render_field

    if method in ("oidn", "oidn_aux"):
        if method == "oidn":
            clean = denoised(image)
        return single_render_field(image, method, clean=clean, **passes)
    return single_render_field(image, method)


def own_rows(scene: dict, method: str, settings, *, replicates: int, factors, draws: int,
             seed: int = 0) -> tuple[list[dict], list[dict]]:
    """The renders' differences (every render n) and the calibration replicates, each with
    the null built from the one render per view."""
    frames, renders = scene["frames"], scene["renders"]
    renders_rows = []
    for k in range(renders["left"].shape[0]):
        rng = np.random.default_rng(derive_seed("own-null", seed, frames.label, method, k))
        d = own_difference({v: renders[v][k] for v in VIEWS}, scene["aux"], frames, method,
                           settings, rng=rng, draws=draws,
                           label=f"{frames.label}|own|{method}|{k}")
        renders_rows.append({"scene": scene["scene"], "render": k, "diff": d[0],
                             "diff_low": d[1], "diff_high": d[2]})
    mu = {v: frames.mean[v].mean(axis=-1) for v in VIEWS}
    law = camera_law(frames.variance["left"], mu["left"], frames.ground_truth["left"]["valid"])
    rng0 = np.random.default_rng(derive_seed("single-render", seed, frames.label))
    render_s = max(render_strength(frames, settings,
                                   camera_residual_variance(frames, law, rng0)), 0.05)
    designs = [("camera", 0.0, 0.0), ("misaligned", 0.0, 0.0)]
    designs += [("planted", f * render_s, f) for f in factors]
    cal = []
    for r in range(replicates):
        rng = np.random.default_rng(derive_seed("own-null-cal", seed, frames.label, method, r))
        gt_r = frames.ground_truth["right"]
        pattern = planted_pattern(gt_r["disparity"], gt_r["valid"], sign=frames.sign, rng=rng)
        for kind, strength, factor in designs:
            v = variance_fields(kind, strength, mean=frames.mean, law=law,
                                render_variance=frames.variance, pattern=pattern, rng=rng)
            one = {view: draw_frames(frames.mean[view], v[view], 1, rng,
                                     channel_correlation=scene["rho_channels"])[0]
                   .astype(np.float64) for view in VIEWS}
            d = own_difference(one, scene["aux"], frames, method, settings, rng=rng,
                               draws=draws, label=f"{frames.label}|own|{r}|{kind}|{factor:g}")
            cal.append({"scene": scene["scene"], "replicate": r, "kind": kind,
                        "strength_factor": factor, "diff": d[0], "diff_low": d[1],
                        "diff_high": d[2]})
    return renders_rows, cal


def own_summary(cal: list[dict], factors) -> dict:
    """False-positive rates, power and the smallest detectable strength of the own-null
    rule (difference interval above 0), one frame per test and the scenes combined."""
    def fires(rows):
        ok = [r for r in rows if math.isfinite(r["diff_low"])]
        return sum(r["diff_low"] > 0 for r in ok), len(ok)

    combined = []
    keys = {(r["replicate"], r["kind"], r["strength_factor"]) for r in cal}
    for key in sorted(keys):
        group = [r for r in cal if (r["replicate"], r["kind"], r["strength_factor"]) == key]
        c = combined_interval([g["diff"] for g in group], [g["diff_low"] for g in group],
                              [g["diff_high"] for g in group])
        combined.append({"replicate": key[0], "kind": key[1], "strength_factor": key[2],
                         "diff": c[0], "diff_low": c[1], "diff_high": c[2]})
    out = {}
    for scope, rows in (("frame", cal), ("combined", combined)):
        entry = {}
        for kind in ("camera", "misaligned"):
            entry[kind] = rate(*fires([r for r in rows if r["kind"] == kind]))
        curve = []
        for f in factors:
            k, n = fires([r for r in rows if r["kind"] == "planted"
                          and r["strength_factor"] == f])
            entry[f"power_{f:g}"] = rate(k, n)
            curve.append((f, k / n if n else math.nan))
        entry["smallest"] = detectable(curve)
        entry["n"] = fires([r for r in rows if r["kind"] == "camera"])[1]
        for kind in ("camera", "misaligned"):
            d = [r["diff"] for r in rows if r["kind"] == kind and math.isfinite(r["diff"])]
            entry[f"mean_{kind}"] = float(np.mean(d)) if d else math.nan
        out[scope] = entry
    return out


def _fmt(x, digits=3) -> str:
    return "nan" if not math.isfinite(float(x)) else f"{float(x):.{digits}f}"


def _interval(v, lo, hi) -> str:
    return f"{_fmt(v)} [{_fmt(lo)}, {_fmt(hi)}]"


def _strength(value, factors) -> str:
    if math.isfinite(float(value)):
        return f"{float(value):.3g}"
    return f"none up to {max(factors):g}x"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+",
                        default=["scene_000", "scene_001", "scene_002", "scene_003"])
    parser.add_argument("--spp", type=int, default=32)
    parser.add_argument("--root", type=Path, default=REPO / "results" / "mitsuba")
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    parser.add_argument("--replicates", type=int, default=12)
    parser.add_argument("--factors", nargs="+", type=float, default=[0.125, 0.5, 1.0, 2.0])
    parser.add_argument("--reps", type=int, default=1000, help="bootstrap replicates")
    parser.add_argument("--own-methods", nargs="*", default=["wavelet_mad"], choices=METHODS,
                        help="candidates measured with the null built from one render")
    parser.add_argument("--own-replicates", type=int, default=6)
    parser.add_argument("--own-draws", type=int, default=4,
                        help="null frames per view (camera and misaligned each)")
    parser.add_argument("--own-factors", nargs="+", type=float, default=[0.5, 1.0, 2.0])
    parser.add_argument("--out", type=Path, help="also write the report here (markdown)")
    parser.add_argument("--rows", type=Path, help="also write every measured row here (CSV)")
    args = parser.parse_args()
    from stereovar.statistics.bootstrap import BootstrapSettings

    settings = AnalysisSettings(bootstrap=BootstrapSettings(reps=args.reps))
    lines: list[str] = []

    def say(text=""):
        print(text, flush=True)
        lines.append(text)

    start = time.perf_counter()
    agree, cal, strengths, channels = [], [], {}, {}
    own_renders: list[dict] = []
    own_cal: dict = {}
    for name in args.scenes:
        t0 = time.perf_counter()
        scene = load_scene(name, spp=args.spp, root=args.root)
        channels[name] = scene["rho_channels"]
        for row in agreement(scene, args.methods, settings):
            agree.append({"scene": name, **row})
        t1 = time.perf_counter()
        rows, strengths[name] = calibration_rows(
            scene, args.methods, settings, replicates=args.replicates, factors=args.factors
        )
        cal += rows
        t2 = time.perf_counter()
        for m in args.own_methods:
            r_rows, c_rows = own_rows(scene, m, settings, replicates=args.own_replicates,
                                      factors=args.own_factors, draws=args.own_draws)
            own_renders += [{"method": m, **r} for r in r_rows]
            own_cal.setdefault(m, []).extend(c_rows)
        if args.own_methods:
            print(f"# {name}: the one-render null {time.perf_counter() - t2:.0f} s",
                  file=sys.stderr, flush=True)
        print(f"# {name}: agreement {t1 - t0:.0f} s, calibration {time.perf_counter() - t1:.0f} s"
              f" (renders' strength {strengths[name]:.3f}, channel correlation "
              f"{channels[name]:.2f})", file=sys.stderr, flush=True)
    table, nulls = calibration_table(cal, methods=("partial",))
    null_of = {(r["scene"], r["transform"]): r for r in nulls}
    paths = ["seeds_n8", *args.methods]

    say(f"# One render per view: {len(args.scenes)} scenes, SPP {args.spp}, "
        f"N = {max(r['render'] for r in agree) + 1} renders per view, {args.replicates} "
        f"calibration replicates per design, strengths {args.factors} x the renders'")
    say()
    say("## Agreement with the N-seed truth (partial rho: mean over the N single renders "
        "+/- sd; its interval: render 0's block bootstrap)")
    say()
    say("| scene | estimator | Spearman vs Eq. 1 (N-1 others), mean [min, max] | partial rho "
        "(mean +/- sd over renders) | render 0: partial rho [95%] | minus matched null "
        "[95%] (render 0) | renders whose difference is above 0 |")
    say("|---|---|---|---|---|---|---|")
    pooled: dict = {p: {"rho": [], "lo": [], "hi": [], "d": [], "dlo": [], "dhi": []}
                    for p in paths}
    for name in args.scenes:
        for p in paths:
            rows = [r for r in agree if r["scene"] == name and r["path"] == p]
            rhos = np.array([r["rho"] for r in rows])
            sps = np.array([r["spearman"] for r in rows])
            first = rows[0]
            null = null_of.get((name, p), {})
            diffs = [difference_interval(r["rho"], r["boot_low"], r["boot_high"],
                                         null.get("null_rho", math.nan),
                                         null.get("null_se", math.nan),
                                         null.get("chance_sd", math.nan)) for r in rows]
            above = sum(d[1] > 0 for d in diffs)
            pooled[p]["rho"].append(first["rho"])
            pooled[p]["lo"].append(first["boot_low"])
            pooled[p]["hi"].append(first["boot_high"])
            for key, val in zip(("d", "dlo", "dhi"), diffs[0], strict=True):
                pooled[p][key].append(val)
            sp_text = "1 (itself)" if p == "seeds_n8" else (
                f"{sps.mean():.3f} [{sps.min():.3f}, {sps.max():.3f}]")
            spread = "" if rhos.size == 1 else f" +/- {rhos.std(ddof=1):.3f}"
            say(f"| {name} | {p} | {sp_text} | {rhos.mean():.3f}{spread} | "
                f"{_interval(first['rho'], first['boot_low'], first['boot_high'])} | "
                f"{_interval(*diffs[0])} | {above}/{len(rows)} |")
    for p in paths:
        c = combined_interval(pooled[p]["rho"], pooled[p]["lo"], pooled[p]["hi"])
        d = combined_interval(pooled[p]["d"], pooled[p]["dlo"], pooled[p]["dhi"])
        say(f"| pooled | {p} | | | {_interval(*c)} | {_interval(*d)} | |")
    say()
    say("## Calibration (partial rho minus its matched null; level 5%, 80% power)")
    say()
    say("| estimator | false positives, camera null | false positives, misaligned null | "
        "power at 1x the renders' strength | smallest detectable, one frame (x the "
        "renders') | smallest detectable, the scenes combined | replicates per design |")
    say("|---|---|---|---|---|---|---|")
    verdicts = {}
    def pick(path, **match):
        return [r for r in table if r["scope"] == "scene" and r["transform"] == path
                and all(r.get(k) == v for k, v in match.items())]

    for p in ["seeds_n8", "seeds_n2", *args.methods]:

        fp = {k: pick(p, check="false_positive_rate", rule="above_null", kind=k) for k in
              ("camera", "misaligned")}
        power1 = pick(p, check="power", strength_factor=1.0)
        smallest = pick(p, check="smallest_detectable")
        s_value = smallest[0]["value"] if smallest else math.nan
        both = [r for r in table if r["scope"] == "combined" and r["transform"] == p
                and r["check"] == "smallest_detectable"]
        s_both = both[0]["value"] if both else math.nan

        def pct(rows):
            if not rows:
                return "n/a"
            r = rows[0]
            return f"{100 * r['value']:.0f}% [{100 * r['low']:.0f}, {100 * r['high']:.0f}]"

        n = fp["camera"][0]["n"] if fp["camera"] else 0
        say(f"| {p} | {pct(fp['camera'])} | {pct(fp['misaligned'])} | {pct(power1)} | "
            f"{_strength(s_value, args.factors)} | {_strength(s_both, args.factors)} | {n} |")
        worst = max((r[0]["value"] for r in fp.values() if r), default=math.nan)
        verdicts[p] = (worst, s_value, s_both, [r[0] for r in fp.values() if r])
    if args.own_methods:
        say()
        say(f"## With the null built from the one render ({args.own_draws} camera and "
            f"{args.own_draws} misaligned null frames per view per test; "
            f"{args.own_replicates} replicates per design)")
        say()
        say("| estimator | scene | the renders: minus its own null [95%] (render 0) | "
            "renders whose difference is above 0 |")
        say("|---|---|---|---|")
        for m in args.own_methods:
            firsts = []
            for name in args.scenes:
                rows = [r for r in own_renders if r["method"] == m and r["scene"] == name]
                firsts.append(rows[0])
                above = sum(r["diff_low"] > 0 for r in rows)
                first = _interval(rows[0]["diff"], rows[0]["diff_low"], rows[0]["diff_high"])
                say(f"| {m} | {name} | {first} | {above}/{len(rows)} |")
            c = combined_interval([r["diff"] for r in firsts], [r["diff_low"] for r in firsts],
                                  [r["diff_high"] for r in firsts])
            say(f"| {m} | pooled | {_interval(*c)} | |")
        say()
        say("| estimator | scope | false positives, camera null | false positives, "
            "misaligned null | " + " | ".join(f"power at {f:g}x" for f in args.own_factors)
            + " | smallest detectable (x the renders') | mean difference on the camera "
            "null | on the misaligned null | tests per design |")
        say("|---|---|---|---|" + "---|" * len(args.own_factors) + "---|---|---|---|")
        for m in args.own_methods:
            summary = own_summary(own_cal[m], args.own_factors)
            for scope, entry in summary.items():
                def pct(r):
                    return f"{100 * r[0]:.0f}% [{100 * r[1]:.0f}, {100 * r[2]:.0f}]"
                say(f"| {m} | {scope} | {pct(entry['camera'])} | {pct(entry['misaligned'])} | "
                    + " | ".join(pct(entry[f"power_{f:g}"]) for f in args.own_factors)
                    + f" | {_strength(entry['smallest'], args.own_factors)} | "
                    f"{_fmt(entry['mean_camera'])} | {_fmt(entry['mean_misaligned'])} | "
                    f"{entry['n']} |")
            verdicts[m + "|own"] = summary
    say()
    say("## Decision")
    say()
    say("A candidate is accepted when, with the null a one-render audit can build, its "
        "false-positive rate on both matched nulls is at the 5% level, it detects a planted "
        "cue below 1x the strength the renders show (the scenes combined, as the audit "
        "reports), and on the renders its difference from that null is above 0 as the "
        "N-seed one is; a candidate that fails with the seed-mean null (which it cannot "
        "have) fails without it too.")
    say()
    for p in args.methods:
        worst, s_frame, s_both, fp_rows = verdicts[p]
        sp = np.mean([r["spearman"] for r in agree if r["path"] == p])
        reasons = []
        if not all(r["meets_target"] != "no" for r in fp_rows):
            reasons.append(f"false positives {100 * worst:.0f}% with the seed-mean null")
        if not (math.isfinite(s_both) and s_both < 1.0):
            reasons.append(f"smallest detectable {_strength(s_both, args.factors)} with the "
                           "seed-mean null (scenes combined)")
        c = combined_interval(pooled[p]["d"], pooled[p]["dlo"], pooled[p]["dhi"])
        if not c[1] > 0:
            reasons.append(f"on the renders its difference from the seed-mean null is "
                           f"{_interval(*c)}, not above 0 as the N-seed one is")
        own = verdicts.get(p + "|own")
        if own is None and not reasons:
            reasons.append("not measured with the null a one-render audit can build")
        if own is not None:
            combined = own["combined"]
            rates = [own[scope][kind] for scope in own for kind in ("camera", "misaligned")]
            if any(r[1] > 0.05 for r in rates):
                reasons.append("false positives with its own null (frame, combined) "
                               + ", ".join(f"{100 * r[0]:.0f}% [{100 * r[1]:.0f}, "
                                           f"{100 * r[2]:.0f}]" for r in rates))
            if not (math.isfinite(combined["smallest"]) and combined["smallest"] < 1.0):
                reasons.append("smallest detectable with its own null "
                               f"{_strength(combined['smallest'], args.own_factors)} "
                               "(scenes combined)")
            rows = [r for r in own_renders if r["method"] == p and r["render"] == 0]
            c = combined_interval([r["diff"] for r in rows], [r["diff_low"] for r in rows],
                                  [r["diff_high"] for r in rows])
            if not c[1] > 0:
                reasons.append(f"on the renders its difference from its own null is "
                               f"{_interval(*c)}, not above 0 as the N-seed one is")
        verdict = "REFUSED" if reasons else "ACCEPTED"
        say(f"- {p}: {verdict}" + (": " + "; ".join(reasons) if reasons else "")
            + f" (mean Spearman with Eq. 1 {sp:.3f}; seed-mean null: worst false positives "
            f"{100 * worst:.0f}%, smallest detectable {_strength(s_frame, args.factors)} one "
            f"frame, {_strength(s_both, args.factors)} scenes combined)")
    say()
    say("The renders' strength (sd of ln sigma^2 beyond intensity and estimation noise): "
        + ", ".join(f"{k} {v:.3f}" for k, v in strengths.items())
        + "; channel correlation of the renders' noise: "
        + ", ".join(f"{k} {v:.2f}" for k, v in channels.items()) + ".")
    say(f"Wall time: {time.perf_counter() - start:.0f} s.")
    if args.out:
        args.out.write_text("\n".join(lines) + "\n")
    if args.rows:
        import csv

        every = ([{"section": "agreement", **r} for r in agree]
                 + [{"section": "calibration", **r} for r in cal]
                 + [{"section": "own_renders", **r} for r in own_renders]
                 + [{"section": "own_calibration", "method": m, **r}
                    for m, rows in own_cal.items() for r in rows])
        columns = list(dict.fromkeys(k for r in every for k in r))
        with args.rows.open("w", newline="") as fh:
            writer = csv.DictWriter(fh, columns)
            writer.writeheader()
            writer.writerows(every)


if __name__ == "__main__":
    main()
