"""A chain's lowest mode shapes from its linear model at the hanging equilibrium (matplotlib).

    conical-pendulum linearize dist/Chain30.fmu --state 'alpha*=0' --state 'beta*=0' --plot modes.png

At the hanging equilibrium the two planes of swinging separate. A link's alpha is its angle
to its parent's, so in that plane link i leans by the sum of the alphas down to it, and the
joint below link k is displaced sideways by the sum over i <= k of l_i times that lean (small
angles). Each mode is drawn as that displacement against the depth, its largest scaled to 1.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import UserError


def plane_modes(model, n_links: int):
    """The modes of the alpha plane: (frequencies in rad/s ascending, angle shapes as columns)."""
    try:
        plane = [model.states.index(f"{s}{i}") for s in ("alpha", "omega") for i in range(n_links)]
    except ValueError:
        raise UserError("mode shapes: the model has no states alpha<i>, omega<i> of a chain") from None
    values, vectors = np.linalg.eig(model.A[np.ix_(plane, plane)])
    keep = [k for k in np.argsort(np.abs(values), kind="stable") if values[k].imag > 0]
    shapes = np.real(
        vectors[:n_links, keep] / vectors[np.argmax(np.abs(vectors[:n_links, keep]), axis=0), keep]
    )
    return np.abs(values[keep]), shapes


def plot_chain_modes(model, lengths, path, count: int = 4) -> Path:
    """The lowest `count` mode shapes of a chain (its links' lengths, top to bottom) to `path`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lengths = np.asarray(lengths, dtype=float)
    omegas, shapes = plane_modes(model, len(lengths))
    depth = np.concatenate([[0.0], np.cumsum(lengths)])
    fig, ax = plt.subplots(figsize=(4.8 + 1.2 * min(count, 6), 6))
    for k in range(min(count, len(omegas))):
        sideways = np.concatenate([[0.0], np.cumsum(lengths * np.cumsum(shapes[:, k]))])
        sideways /= sideways[np.argmax(np.abs(sideways))]
        label = f"mode {k + 1}: {omegas[k]:.4g} rad/s, {omegas[k] / (2 * math.pi):.4g} Hz"
        ax.plot(sideways + 2.5 * k, -depth, marker="o" if len(lengths) <= 30 else None, ms=3, label=label)
        ax.axvline(2.5 * k, color="0.8", lw=0.8, zorder=0)
    ax.set_xticks([])
    ax.set_xlabel("sideways displacement, each mode scaled to 1 at its largest (offset per mode)")
    ax.set_ylabel("depth below the pivot [m]")
    fig.suptitle(f"lowest modes of a {len(lengths)}-link chain, hanging at rest")
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, fontsize=8, frameon=False)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
