"""Figures of the speed-against-error report (matplotlib, Agg backend)."""

import csv
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

COLORS = {"ours": "#d62728", "ours_rays": "#9467bd", "eevee": "#1f77b4", "cycles": "#2ca02c"}
MARKERS = {"ours": "o", "ours_rays": "D", "eevee": "s", "cycles": "^"}


def _engine_rows(rows, key):
    return sorted((r for r in rows if r["engine"] == key), key=lambda r: r["seconds"])


def _plot_metric(ax, rows, info, labels, metric, noise_key, title):
    for key in ("ours", "ours_rays", "eevee", "cycles"):
        rs = _engine_rows(rows, key)
        if not rs:
            continue
        ts = [r["seconds"] for r in rs]
        es = [r[metric] for r in rs]
        ax.plot(ts, es, marker=MARKERS[key], color=COLORS[key], label=labels[key])
        for r in rs:
            ax.annotate(str(r["samples"]), (r["seconds"], r[metric]), textcoords="offset points",
                        xytext=(4, 4), fontsize=7, color=COLORS[key])
    ax.axhline(info[noise_key], color="0.4", ls=":", lw=1,
               label=f"reference noise ({info['spp']} spp)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("render time in Blender [s]")
    ax.set_ylabel(title)
    ax.grid(True, which="both", alpha=0.25)


def error_plot(path, name, rows, info, labels):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    _plot_metric(axes[0], rows, info, labels, "rmse", "noise_rmse", "RMSE vs reference (Combined RGB)")
    _plot_metric(axes[1], rows, info, labels, "relmse", "noise_relmse", "relMSE vs reference")
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{name}: error against time ({info['width']}×{info['height']}, "
                 "labels = samples; 2 cores, llvmpipe)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def overview(path, rows, infos, labels):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    n = len(infos)
    cols = min(3, n)
    nrows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(nrows, cols, figsize=(5.2 * cols, 3.9 * nrows), squeeze=False)
    for ax, info in zip(axes.flat, infos):
        _plot_metric(ax, [r for r in rows if r["scene"] == info["scene"]], info, labels, "rmse",
                     "noise_rmse", "RMSE")
        ax.set_title(info["scene"], fontsize=10)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def to_srgb(x):
    """Blender's Standard view transform: clip to [0, 1], sRGB OETF."""
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def _pick(rows, key, target_seconds=None):
    rs = _engine_rows(rows, key)
    if not rs:
        return None
    if target_seconds is None:
        return max(rs, key=lambda r: r["samples"])
    return min(rs, key=lambda r: abs(math.log(r["seconds"] / target_seconds)))


def side_by_side(path, name, rows, images, info, labels):
    """Top: reference, ours (most samples), EEVEE and Cycles at the time
    closest to ours. Bottom: the reference's own noise |a-b|/2 and
    |engine - reference| (mean over RGB), one shared colour scale."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    ref = images["ref"]
    ours = _pick(rows, "ours")
    t = ours["seconds"] if ours else None
    picks = [("ours", ours), ("eevee", _pick(rows, "eevee", t)), ("cycles", _pick(rows, "cycles", t))]
    errs = {}
    for key, r in picks:
        if r is not None:
            errs[key] = np.abs(images[(key, r["samples"])] - ref).mean(-1)
    vmax = max([float(np.percentile(e, 99.5)) for e in errs.values()] + [1e-6])
    h, w = ref.shape[:2]
    fig, axes = plt.subplots(2, 4, figsize=(4 * w / 80 + 1.0, 2 * h / 80 + 1.2),
                             gridspec_kw={"wspace": 0.04, "hspace": 0.14})
    axes[0, 0].imshow(to_srgb(ref), interpolation="nearest")
    axes[0, 0].set_title(f"Cycles reference, {info['spp']} spp", fontsize=8)
    im = axes[1, 0].imshow(images["ref_noise"], cmap="inferno", vmin=0, vmax=vmax, interpolation="nearest")
    axes[1, 0].set_title(f"reference noise |a−b|/2, RMSE {info['noise_rmse']:.3g}", fontsize=8)
    for col, (key, r) in enumerate(picks, start=1):
        if r is None:
            axes[0, col].axis("off")
            axes[1, col].axis("off")
            continue
        x = images[(key, r["samples"])]
        axes[0, col].imshow(to_srgb(x), interpolation="nearest")
        axes[0, col].set_title(f"{labels[key]}, {r['samples']} spp, {r['seconds']:.2f} s", fontsize=8)
        axes[1, col].imshow(errs[key], cmap="inferno", vmin=0, vmax=vmax, interpolation="nearest")
        axes[1, col].set_title(f"|error|, RMSE {r['rmse']:.3g}, mean/ref {r['mean_ratio']:.3f}", fontsize=8)
    for ax in axes.flat:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"{name}: top = Standard view (sRGB, clipped); bottom = |x − ref| averaged over RGB, "
                 f"scale 0..{vmax:.3g} (99.5th percentile)", fontsize=9)
    fig.colorbar(im, ax=axes[1, :].tolist(), fraction=0.015, pad=0.01)
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)


def _interior(labels, radius=1):
    h, w = labels.shape
    ok = np.ones((h, w), bool)
    padded = np.pad(labels, radius, mode="edge")
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            ok &= padded[radius + dy:radius + dy + h, radius + dx:radius + dx + w] == labels
    ok[:radius, :] = ok[-radius:, :] = False
    ok[:, :radius] = ok[:, -radius:] = False
    return ok


def per_object(path, name, rows, images, info, ref, engines=("ours", "ours_rays", "eevee", "cycles"),
               min_pixels=40, label="reference"):
    """Mean Combined per object (Cycles' IndexOB of the reference, interior
    pixels only, so edges do not count) of each engine at its most samples,
    over the reference's. Writes a CSV and returns the rows."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    index = np.rint(info["index"]).astype(np.int64)
    interior = _interior(index)
    picks = {key: _pick(rows, key) for key in engines}
    names = info.get("pass_index_names") or {}
    out = []
    for value in np.unique(index):
        mask = interior & (index == value)
        if mask.sum() < min_pixels:
            continue
        rm = ref[mask].mean(0)
        if rm.sum() <= 1e-4:    # black background (box_room): a ratio means nothing
            continue
        row = {"scene": name, "against": label, "pass_index": int(value),
               "objects": " ".join(names.get(str(int(value)), [])),
               "pixels": int(mask.sum()), "ref_r": rm[0], "ref_g": rm[1], "ref_b": rm[2]}
        for key, r in picks.items():
            if r is None:
                continue
            xm = images[(key, r["samples"])][mask].mean(0)
            row[f"{key}_samples"] = r["samples"]
            row[f"{key}_ratio"] = float(xm.sum() / rm.sum()) if rm.sum() > 0 else float("nan")
            row[f"{key}_ratio_rgb"] = " ".join(f"{v:.3f}" for v in (xm / np.maximum(rm, 1e-12)))
        out.append(row)
    if out:
        with open(path, "w", newline="") as f:
            fields = list(dict.fromkeys(k for row in out for k in row))
            wr = csv.DictWriter(f, fieldnames=fields)
            wr.writeheader()
            for row in out:
                wr.writerow(row)
    return out


def unoccluded_view(path, name, rows, images, info, labels, key="ours"):
    """Ours (most samples; shadows off) against the shadow-free Cycles
    reference: what is left once shadows are taken out of the comparison."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    ours = _pick(rows, key)
    if ours is None or "ref_unoccluded" not in images:
        return
    ref = images["ref_unoccluded"]
    uinfo = info["unoccluded"]
    x = images[(key, ours["samples"])]
    err = np.abs(x - ref).mean(-1)
    lum = lambda im: im @ np.array([0.2126, 0.7152, 0.0722])  # noqa: E731
    signed = (lum(x) - lum(ref)) / np.maximum(lum(ref), 0.02)
    vmax = max(float(np.percentile(err, 99.5)), 1e-6)
    h, w = ref.shape[:2]
    fig, axes = plt.subplots(1, 5, figsize=(5 * w / 80 + 1.5, h / 80 + 0.9))
    axes[0].imshow(to_srgb(ref), interpolation="nearest")
    axes[0].set_title(f"Cycles, no shadows, {uinfo['spp']} spp", fontsize=8)
    axes[1].imshow(to_srgb(x), interpolation="nearest")
    axes[1].set_title(f"{labels[key]}, {ours['samples']} spp", fontsize=8)
    axes[2].imshow(images["ref_unoccluded_noise"], cmap="inferno", vmin=0, vmax=vmax, interpolation="nearest")
    axes[2].set_title(f"reference noise, RMSE {uinfo['noise_rmse']:.3g}", fontsize=8)
    im = axes[3].imshow(err, cmap="inferno", vmin=0, vmax=vmax, interpolation="nearest")
    axes[3].set_title(f"|ours − ref|, RMSE {ours.get('rmse_unocc', float('nan')):.3g} (0..{vmax:.3g})",
                      fontsize=8)
    fig.colorbar(im, ax=axes[3], fraction=0.03, pad=0.01)
    im2 = axes[4].imshow(signed, cmap="coolwarm", vmin=-0.25, vmax=0.25, interpolation="nearest")
    axes[4].set_title("luminance (ours − ref)/ref, ±25 %", fontsize=8)
    fig.colorbar(im2, ax=axes[4], fraction=0.03, pad=0.01)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"{name}: ours against Cycles where no object blocks any light "
                 "(everything but shadows)", fontsize=9)
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)
