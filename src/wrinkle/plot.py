"""Pictures with matplotlib (an optional dependency: pip install "wrinkle[plot]")."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wrinkle.verification.shear_stretch import shear_stretch_curves


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # pragma: no cover - depends on the installation
        raise SystemExit(
            'wrinkle: pictures need matplotlib; install it with pip install "wrinkle[plot]"'
        ) from None
    return plt


def plot_shear_stretch(rows, path: Path, shear: float) -> None:
    """Two panels like the paper's Figs. 6 and 7: F1(v) and F2(v) for each anisotropy f.

    Lines: the independent homogeneous solution; markers: finite-element results (filled where
    the elements are wrinkled, open where taut); a dotted line marks the taut/wrinkled change.
    """
    from wrinkle.demo import paper_material

    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    anisotropies = sorted({r.f for r in rows})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for colour, f in zip(colours, anisotropies):
        mine = [r for r in rows if r.f == f]
        v = np.array([r.v for r in mine])
        fine = np.linspace(v.min(), v.max(), 81)
        curves = shear_stretch_curves(paper_material(f), shear, fine)
        change = [
            0.5 * (fine[i] + fine[i + 1])
            for i in range(fine.size - 1)
            if curves.state[i] != curves.state[i + 1]
        ]
        for ax, name, analytic in ((axes[0], "F1", curves.F1), (axes[1], "F2", curves.F2)):
            ax.plot(fine, analytic, "-", color=colour, lw=1.2, label=f"analytic, f = {f:g}")
            values = np.array([getattr(r, name) for r in mine])
            wrinkled = np.array([r.state == "wrinkled" for r in mine])
            ax.plot(v[wrinkled], values[wrinkled], "o", color=colour, ms=5,
                    label=f"FE wrinkled, f = {f:g}")
            ax.plot(v[~wrinkled], values[~wrinkled], "o", mfc="none", color=colour, ms=5,
                    label=f"FE taut, f = {f:g}")
            for x in change:
                ax.axvline(x, color=colour, ls=":", lw=1)
    for ax, name, what in (
        (axes[0], "F1", "along the shear (x)"), (axes[1], "F2", "along the stretch (y)")
    ):
        ax.set_xlabel("stretching distance v (length units, L = 1)")
        ax.set_ylabel(f"{name}: top-edge force {what} (force units)")
        ax.grid(True, alpha=0.3)
    axes[0].set_title(f"Shear force, gamma = {shear:g} held (cf. paper Fig. 6)")
    axes[1].set_title("Stretching force (cf. paper Fig. 7)")
    axes[1].legend(fontsize=7, ncol=3, loc="upper left")
    fig.savefig(path, dpi=120)
    plt.close(fig)
