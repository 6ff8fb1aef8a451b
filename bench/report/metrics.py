"""Image error metrics and the equal-time / equal-error comparison.

Pure numpy (runs in the system python3 next to matplotlib).

Errors are on the Combined pass, RGB only (alpha ignored), scene-linear:
  RMSE   = sqrt(mean((x - y)^2))                 over pixels and RGB
  relMSE = mean((x - y)^2 / (y^2 + 0.01))        y = reference
  PSNR   = 10 log10(peak^2 / MSE), peak = max of the reference RGB
"""

import math

import numpy as np


def read_rgb(path):
    """(H, W, 3) float32 Combined RGB of an EXR (single layer R,G,B or
    multilayer ViewLayer.Combined.R/G/B), top row first (file order), and a
    dict of every channel (for IndexOB and the like)."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError(f"cannot open {path}: {oiio.geterror()}")
    channels = {}
    try:
        sub = 0
        while inp.seek_subimage(sub, 0):
            spec = inp.spec()
            px = inp.read_image(0, spec.nchannels, oiio.FLOAT)
            if px is None:
                raise RuntimeError(f"cannot read {path}: {inp.geterror()}")
            px = np.asarray(px, np.float32).reshape(spec.height, spec.width, spec.nchannels)
            for c, name in enumerate(spec.channelnames):
                channels[name] = px[:, :, c]
            sub += 1
    finally:
        inp.close()
    for prefix in ("", "ViewLayer.Combined.", "Combined."):
        if all(prefix + c in channels for c in "RGB"):
            return np.stack([channels[prefix + c] for c in "RGB"], -1), channels
    for name in channels:   # any <layer>.Combined.R
        if name.endswith(".Combined.R"):
            base = name[:-1]
            return np.stack([channels[base + c] for c in "RGB"], -1), channels
    raise RuntimeError(f"{path}: no Combined RGB among {sorted(channels)[:12]}")


def errors(x, ref, peak=None):
    x = np.asarray(x, np.float64)
    ref = np.asarray(ref, np.float64)
    d2 = (x - ref) ** 2
    mse = float(d2.mean())
    peak = float(ref.max()) if peak is None else float(peak)
    return {
        "mse": mse,
        "rmse": math.sqrt(mse),
        "relmse": float((d2 / (ref ** 2 + 0.01)).mean()),
        "psnr": 10.0 * math.log10(peak ** 2 / mse) if mse > 0 else float("inf"),
        "mean_ratio": float(x.mean() / ref.mean()) if ref.mean() != 0 else float("nan"),
    }


def reference_noise(a, b, ref=None):
    """Remaining noise of ref = (a + b) / 2 from two independent halves:
    E[(a - b)^2] = 2 var_half and var_ref = var_half / 2, so var_ref =
    mean((a - b)^2) / 4 (the rms of (a - b) / 2)."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    ref = (a + b) / 2 if ref is None else ref
    d2 = ((a - b) / 2.0) ** 2
    return {"mse": float(d2.mean()), "rmse": math.sqrt(float(d2.mean())),
            "relmse": float((d2 / (ref ** 2 + 0.01)).mean())}


# ---------------------------------------------------------------------------
# equal time / equal error
# ---------------------------------------------------------------------------

def _interp_loglog(xs, ys, x):
    """Piecewise-linear interpolation in log-log of points (xs ascending)."""
    if not xs or x < xs[0] or x > xs[-1]:
        return None
    for i in range(len(xs) - 1):
        if xs[i] <= x <= xs[i + 1]:
            if xs[i + 1] == xs[i]:
                return ys[i]
            t = (math.log(x) - math.log(xs[i])) / (math.log(xs[i + 1]) - math.log(xs[i]))
            return math.exp(math.log(ys[i]) + t * (math.log(ys[i + 1]) - math.log(ys[i])))
    return ys[-1]


class Curve:
    """Measured (samples, time, error) points of one engine on one scene.

    error_at_time(t) and time_for_error(e) interpolate in log-log between
    measured points. Outside the measured range they return a bound
    (kind '<' or '>') unless a model is given (Cycles, see CyclesModel)."""

    def __init__(self, points, model=None):
        self.points = sorted(points, key=lambda p: p[1])  # (samples, seconds, error)
        self.model = model

    def error_at_time(self, t):
        ts = [p[1] for p in self.points]
        es = [p[2] for p in self.points]
        v = _interp_loglog(ts, es, t)
        if v is not None:
            return v, "="
        if self.model is not None:
            m = self.model.error_at_time(t)
            if m is not None:
                return m, "~"
        if t < ts[0]:
            return None, "slower"        # cannot render that fast at all
        return es[-1], ">="              # more time was not measured; error at most ~ this

    def time_for_error(self, e):
        # walk from fast to slow, first crossing below e
        pts = self.points
        if pts[0][2] <= e:
            if self.model is not None:
                m = self.model.time_for_error(e)
                if m is not None and m <= pts[0][1]:
                    return m, "~"
            return pts[0][1], "<="
        for i in range(len(pts) - 1):
            (_, t0, e0), (_, t1, e1) = pts[i], pts[i + 1]
            if e0 > e >= e1:
                u = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
                return math.exp(math.log(t0) + u * (math.log(t1) - math.log(t0))), "="
        if self.model is not None:
            m = self.model.time_for_error(e)
            if m is not None:
                return m, "~"
            return None, "never"
        return pts[-1][1], ">"           # not reached within the measured range


class CyclesModel:
    """Cycles is unbiased: MSE(n) = a + b/n, a = the reference's own noise MSE
    (measured), b from the point with the most samples (1 sample is worse than
    1/n predicts: no stratification, so a least-squares fit over all points
    would be dominated by it); time(n) = t0 + k n fitted. Used only outside the
    measured range (i.e. beyond the most samples), marked '~' in the tables."""

    def __init__(self, samples, seconds, mses, ref_mse):
        n = np.asarray(samples, np.float64)
        t = np.asarray(seconds, np.float64)
        m = np.asarray(mses, np.float64)
        self.a = float(ref_mse)
        last = int(np.argmax(n))
        self.b = float(max(n[last] * (m[last] - self.a), 1e-30))
        if len(n) >= 2:
            k, t0 = np.polyfit(n, t, 1)
        else:
            k, t0 = t[0] / n[0], 0.0
        self.k, self.t0 = float(max(k, 1e-9)), float(max(t0, 0.0))

    def error_at_time(self, t):
        n = (t - self.t0) / self.k
        if n < 1:
            return None
        return math.sqrt(self.a + self.b / n)

    def time_for_error(self, e):
        if e * e <= self.a:
            return None
        n = self.b / (e * e - self.a)
        return self.t0 + self.k * max(n, 1.0)
