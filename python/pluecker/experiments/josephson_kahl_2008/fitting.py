"""Figures 1-2 of Josephson & Kahl 2008 (section 3.1): residuals of fitted lines and conics.

``pluecker.fitting_residual_samples`` draws random 1000 x 1000 images with one line (21 points) and one
ellipse (63 points), adds 1 px Gaussian noise, refits both and records the residual of the true primitive
in the frame of the fitted one (2 entries for lines, 5 for conics). Plotted: histograms with a Gaussian of
the same mean and standard deviation (as the paper), and the same residuals whitened by the covariance
``fit_line`` / ``fit_conic`` predict, against the standard normal. Skewness, excess kurtosis and the
Kolmogorov-Smirnov distance quantify "near Gaussian".
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

import pluecker

from .common import markdown_table

DRAWS = 100_000
DRAWS_QUICK = 2_000
IMAGE_SIZE = 1000.0
SIGMA_PX = 1.0


def _normal_cdf(x: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + np.vectorize(math.erf)(x / math.sqrt(2.0)))


def residual_statistics(values: np.ndarray) -> dict[str, float]:
    """Mean, standard deviation, skewness, excess kurtosis of one residual entry, and the Kolmogorov-
    Smirnov distance of its standardised values from the standard normal."""
    mean, std = float(np.mean(values)), float(np.std(values))
    z = np.sort((values - mean) / std)
    n = len(z)
    cdf = _normal_cdf(z)
    ks = float(max(np.max(np.arange(1, n + 1) / n - cdf), np.max(cdf - np.arange(n) / n)))
    return {"mean": mean, "std": std, "skewness": float(np.mean(z**3)), "excess_kurtosis": float(np.mean(z**4) - 3.0),
            "ks_distance": ks}


def run(draws: int, seed: int) -> dict[str, np.ndarray]:
    samples = pluecker.fitting_residual_samples(draws, size=IMAGE_SIZE, sigma=SIGMA_PX, seed=seed)
    return {k: np.asarray(v) for k, v in samples.items()}


def summary(samples: dict[str, np.ndarray]) -> dict[str, Any]:
    out: dict[str, Any] = {"draws": int(len(samples["line"]))}
    for kind in ("line", "conic"):
        raw, white = samples[kind], samples[f"{kind}_whitened"]
        out[kind] = [{"raw": residual_statistics(raw[:, j]), "whitened": residual_statistics(white[:, j])}
                     for j in range(raw.shape[1])]
        out[f"{kind}_whitened_covariance"] = np.cov(white.T).tolist()
    return out


def table(summary: dict[str, Any]) -> str:
    headers = ["residual", "std (raw)", "skewness", "excess kurtosis", "KS distance", "whitened mean",
               "whitened std", "whitened KS distance"]
    rows = []
    for kind, label in (("line", "line"), ("conic", "conic")):
        for j, entry in enumerate(summary[kind]):
            raw, white = entry["raw"], entry["whitened"]
            rows.append([f"{label} r{j + 1}", f"{raw['std']:.4g}", f"{raw['skewness']:.3f}",
                         f"{raw['excess_kurtosis']:.3f}", f"{raw['ks_distance']:.4f}", f"{white['mean']:.3f}",
                         f"{white['std']:.3f}", f"{white['ks_distance']:.4f}"])
    return markdown_table(headers, rows)


def figures(samples: dict[str, np.ndarray], out: Path) -> list[Path]:
    """Figure 1 (line, 2 entries) and Figure 2 (conic, 5 entries): raw residuals with the Gaussian of the
    same mean and standard deviation (top row, as the paper), whitened residuals with the standard
    normal (bottom row)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = []
    for number, kind, unit in (("1", "line", "px"), ("2", "conic", "")):
        raw, white = samples[kind], samples[f"{kind}_whitened"]
        k = raw.shape[1]
        fig, axes = plt.subplots(2, k, figsize=(3.2 * k, 5.6), constrained_layout=True, squeeze=False)
        for j in range(k):
            for row, (values, label) in enumerate(((raw[:, j], f"r{j + 1} {unit}".strip()),
                                                   (white[:, j], f"whitened r{j + 1}"))):
                ax = axes[row, j]
                mean, std = (float(np.mean(values)), float(np.std(values))) if row == 0 else (0.0, 1.0)
                lo, hi = np.percentile(values, [0.05, 99.95])
                ax.hist(values, bins=80, range=(lo, hi), density=True, color="tab:blue", alpha=0.6)
                grid = np.linspace(lo, hi, 400)
                ax.plot(grid, np.exp(-0.5 * ((grid - mean) / std) ** 2) / (std * math.sqrt(2 * math.pi)),
                        color="tab:red", lw=1.2, label="Gaussian" if row == 0 else "N(0, 1)")
                ax.set_xlabel(label)
                ax.legend(fontsize="x-small")
        fig.suptitle(f"Figure {number}: residuals of {kind}s fitted to {21 if kind == 'line' else 63} points\n"
                     f"with {SIGMA_PX:g} px noise ({len(raw)} draws); top: raw,\nbottom: whitened by the "
                     "predicted covariance", fontsize="small")
        path = out / f"figure{number}_{kind}_residuals.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        files.append(path)
    return files
