"""Small torch MLPs trained many at once, with nested selection by group.

One network maps standardised conditions ``x`` (``p``) to a target vector ``y`` (``m``;
e.g. sine coefficients of a residual curve, so every predicted curve is zero at both
ends by construction)::

    yhat(x) = y_0 + s_y * (W_2^T tanh(W_1^T (x - mu) / sd + b_1) + b_2)

``mu``, ``sd`` (per feature) and ``s_y`` (one scalar) come from the network's own
training rows; the base ``y_0`` is either the mean training target ``y_bar`` (``"mean"``:
the null model in the target's frame) or 0 (``"zero"``: the slerp itself, no residual).
``W_2`` and ``b_2`` start at zero, so every network starts at that analytic nominal.
Loss: mean squared error in units of ``s_y`` plus ``weight_decay * (|W_1|^2 + |W_2|^2)``;
full-batch Adam.

Validation (for early stopping and selection) uses either the mean squared error or,
with a :class:`CurveCriterion`, the papers' criterion itself: the median over the
validation rows of ``max_t |curve_hat(t) - curve(t)|``.

``B`` networks (outer folds x candidates x inner folds) are one set of batched tensors
``(B, p, h)``, trained together with ``torch.bmm``; each sees only its rows through a
mask. Every network starts from the same seeded initialisation, so folds differ only by
their data. Deterministic on CPU: ``torch.use_deterministic_algorithms(True)``, one
thread, float32, a seeded generator.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import NDArray

from motion_envs._typing import FloatArray

__all__ = [
    "CurveCriterion",
    "MLPConfig",
    "TrainedNetworks",
    "deterministic_torch",
    "forward",
    "train_networks",
]


@dataclass(frozen=True)
class MLPConfig:
    """Hyper-parameters of the residual MLP (the candidates are chosen by nested CV).

    Attributes
    ----------
    hidden:
        Width of the single hidden layer.
    max_epochs:
        Full-batch Adam steps at most; the number used is chosen on inner validation
        folds (early stopping), from 0 (the nominal) to ``max_epochs``.
    lr:
        Adam learning rate.
    weight_decays:
        Candidate L2 penalties, chosen per outer fold on its inner validation folds.
    bases:
        Candidate nominals the network starts from and corrects: ``"mean"`` (the mean
        training target) and/or ``"zero"``; chosen like the penalties.
    inner_splits:
        Inner folds by group (at most the number of training groups).
    seed:
        Seed of the initialisation.
    """

    hidden: int = 32
    max_epochs: int = 150
    lr: float = 5e-3
    weight_decays: tuple[float, ...] = (1e-2, 1e-1)
    bases: tuple[str, ...] = ("mean", "zero")
    inner_splits: int = 3
    seed: int = 0

    def __post_init__(self) -> None:
        if self.hidden < 1 or self.max_epochs < 0 or not self.lr > 0:
            raise ValueError(f"hidden >= 1, max_epochs >= 0 and lr > 0 required; got {self}")
        if not self.weight_decays or any(w < 0 for w in self.weight_decays):
            raise ValueError(f"weight_decays must be non-empty and >= 0; got {self.weight_decays}")
        if not self.bases or any(b not in ("mean", "zero") for b in self.bases):
            raise ValueError(f"bases must be among ('mean', 'zero'); got {self.bases}")
        if self.inner_splits < 2:
            raise ValueError(f"inner_splits must be >= 2; got {self.inner_splits}")


@contextmanager
def deterministic_torch(threads: int = 1) -> Iterator[None]:
    """Deterministic CPU torch inside the block (restores the previous settings)."""
    old_threads = torch.get_num_threads()
    old_det = torch.are_deterministic_algorithms_enabled()
    torch.set_num_threads(threads)
    torch.use_deterministic_algorithms(True)
    try:
        yield
    finally:
        torch.use_deterministic_algorithms(old_det)
        torch.set_num_threads(old_threads)


@dataclass(frozen=True)
class CurveCriterion:
    """The papers' criterion on curves decoded from the outputs.

    Row ``n``'s curve is ``basis @ y.reshape(K, D)`` (``basis`` ``(T, K)``); its error is
    ``scale_n * max_t |curve(t) - target_n(t)|`` with ``target`` ``(N, T, D)`` or
    ``(B, N, T, D)`` (per network) and ``scale`` ``(N,)`` (e.g. the path-frame scale:
    the path frame is a rotation times ``s``, so body-frame norms are ``s`` times
    path-frame ones).
    """

    basis: FloatArray
    target: FloatArray
    scale: FloatArray

    def row_errors(self, out: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
        """``(B, N)`` errors of outputs ``(B, N, K D)``."""
        K = self.basis.shape[1]
        B, N, m = out.shape
        curves = torch.einsum(
            "tk,bnkd->bntd",
            torch.as_tensor(self.basis, dtype=out.dtype),
            out.reshape(B, N, K, m // K),
        )
        dist = torch.linalg.vector_norm(curves - target, dim=3).amax(dim=2)
        scaled: torch.Tensor = dist * torch.as_tensor(self.scale, dtype=out.dtype)[None, :]
        return scaled


@dataclass
class TrainedNetworks:
    """Result of :func:`train_networks`.

    Attributes
    ----------
    val_loss:
        ``(B, max_epochs + 1)`` validation error after ``e`` steps: mean squared error
        (original units, per output value), or with a criterion the median of the rows'
        criterion (NaN without validation rows).
    predictions:
        ``(B, N, m)`` each network's predictions of every row at its stop epoch.
    params:
        Name -> ``(B, ...)`` array: weights at the stop epoch and the normalisation
        (``x_mean``, ``x_scale``, ``y_mean``, ``y_scale``).
    """

    val_loss: FloatArray
    predictions: FloatArray
    params: dict[str, FloatArray]


def forward(params: dict[str, torch.Tensor], X: torch.Tensor) -> torch.Tensor:
    """``(B, N, m)`` outputs of ``B`` networks on rows ``X`` (``(N, p)`` or ``(B, N, p)``)."""
    Xs = (X - params["x_mean"][:, None, :]) / params["x_scale"][:, None, :]
    h = torch.tanh(torch.bmm(Xs, params["W1"]) + params["b1"][:, None, :])
    out = torch.bmm(h, params["W2"]) + params["b2"][:, None, :]
    return params["y_base"][:, None, :] + params["y_scale"][:, None, None] * out


def _masked_stats(A: torch.Tensor, masks: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Per-network mean and sd over its masked rows; ``A`` is ``(N, c)`` or ``(B, N, c)``."""
    w = masks / masks.sum(dim=1, keepdim=True)
    if A.ndim == 2:
        A = A.expand(masks.shape[0], *A.shape)
    mean = torch.einsum("bn,bnc->bc", w, A)
    var = torch.einsum("bn,bnc->bc", w, A * A) - mean * mean
    return mean, torch.sqrt(torch.clamp(var, min=0.0))


def train_networks(
    X: FloatArray,
    Y: FloatArray,
    train_masks: NDArray[np.bool_],
    val_masks: NDArray[np.bool_] | None,
    weight_decays: FloatArray,
    config: MLPConfig,
    stop_epochs: NDArray[np.int64] | None = None,
    bases: NDArray[np.str_] | None = None,
    criterion: CurveCriterion | None = None,
) -> TrainedNetworks:
    """Train ``B`` networks at once; network ``b`` fits rows ``train_masks[b]``.

    Parameters
    ----------
    X, Y:
        ``(N, p)`` conditions and ``(N, m)`` targets of every row, or ``(B, N, m)``
        targets: one set per network (e.g. residuals against a per-fold timing model).
    train_masks, val_masks:
        ``(B, N)`` rows each network trains / is validated on (``val_masks`` may be None).
    weight_decays:
        ``(B,)`` L2 penalty of each network.
    stop_epochs:
        ``(B,)`` epoch at which each network's weights and predictions are taken
        (default: ``config.max_epochs`` for all); training runs to their maximum.
    bases:
        ``(B,)`` ``"mean"`` or ``"zero"`` per network (default all ``"mean"``).
    criterion:
        Validation by the papers' criterion instead of the mean squared error.
    """
    tm = torch.as_tensor(np.asarray(train_masks, dtype=np.float32))
    B, N = tm.shape
    if B == 0:
        raise ValueError("train_masks must hold at least one network")
    if np.any(np.asarray(train_masks).sum(axis=1) < 2):
        raise ValueError("every network needs at least 2 training rows")
    vm = (
        torch.zeros_like(tm)
        if val_masks is None
        else torch.as_tensor(np.asarray(val_masks, dtype=np.float32))
    )
    stops = (
        np.full(B, config.max_epochs, dtype=np.int64)
        if stop_epochs is None
        else np.asarray(stop_epochs, dtype=np.int64)
    )
    epochs = int(stops.max()) if stop_epochs is not None else config.max_epochs
    with deterministic_torch():
        Xt = torch.as_tensor(np.asarray(X, dtype=np.float32))
        Yt = torch.as_tensor(np.asarray(Y, dtype=np.float32))
        Yt = Yt.expand(B, *Yt.shape) if Yt.ndim == 2 else Yt
        if Yt.shape[:2] != (B, N):
            raise ValueError(f"Y must be ({N}, m) or ({B}, {N}, m); got {tuple(Yt.shape)}")
        p, m, h = Xt.shape[1], Yt.shape[2], config.hidden
        x_mean, x_sd = _masked_stats(Xt, tm)
        x_scale = torch.where(x_sd > 1e-12, x_sd, torch.ones_like(x_sd))
        y_mean, _ = _masked_stats(Yt, tm)
        resid = Yt - y_mean[:, None, :]
        y_var = (tm[:, :, None] * resid**2).sum(dim=(1, 2)) / (tm.sum(dim=1) * m)
        y_scale = torch.sqrt(torch.clamp(y_var, min=1e-24))
        gen = torch.Generator().manual_seed(int(config.seed))
        bound = 1.0 / np.sqrt(p)
        W1_0 = (torch.rand(p, h, generator=gen, dtype=torch.float32) * 2 - 1) * bound
        b1_0 = (torch.rand(h, generator=gen, dtype=torch.float32) * 2 - 1) * bound
        use_mean = torch.as_tensor(
            np.ones(B, bool) if bases is None else np.asarray(bases) == "mean"
        )
        y_base = torch.where(use_mean[:, None], y_mean, torch.zeros_like(y_mean))
        fixed = {"x_mean": x_mean, "x_scale": x_scale, "y_base": y_base, "y_scale": y_scale}
        crit_target = None
        if criterion is not None:
            crit_target = torch.as_tensor(np.asarray(criterion.target, dtype=np.float32))
            if crit_target.ndim == 3:
                crit_target = crit_target.expand(B, *crit_target.shape)
        learn = {
            "W1": W1_0.expand(B, p, h).clone().requires_grad_(True),
            "b1": b1_0.expand(B, h).clone().requires_grad_(True),
            "W2": torch.zeros(B, h, m, dtype=torch.float32, requires_grad=True),
            "b2": torch.zeros(B, m, dtype=torch.float32, requires_grad=True),
        }
        wd = torch.as_tensor(np.asarray(weight_decays, dtype=np.float32))
        opt = torch.optim.Adam(list(learn.values()), lr=config.lr)
        n_train = tm.sum(dim=1)
        n_val = vm.sum(dim=1)
        val_loss = np.full((B, epochs + 1), np.nan)
        snap = {k: v.detach().clone() for k, v in learn.items()}
        pred = torch.zeros(B, N, m, dtype=torch.float32)

        def record(epoch: int, out: torch.Tensor) -> None:
            with torch.no_grad():
                if criterion is None:
                    err = ((out - Yt) ** 2).sum(dim=2)
                    val = (vm * err).sum(dim=1) / (n_val * m)
                else:
                    assert crit_target is not None
                    rows = criterion.row_errors(out, crit_target)
                    val = torch.nanmedian(torch.where(vm > 0, rows, torch.nan), dim=1).values
                val_loss[:, epoch] = np.where(n_val.numpy() > 0, val.numpy(), np.nan)
                hit = torch.as_tensor(stops == epoch)
                if bool(hit.any()):
                    for k, v in learn.items():
                        snap[k][hit] = v.detach()[hit]
                    pred[hit] = out.detach()[hit]

        for epoch in range(epochs + 1):
            out = forward({**fixed, **learn}, Xt.expand(B, N, p))
            record(epoch, out)
            if epoch == epochs:
                break
            err = (((out - Yt) / y_scale[:, None, None]) ** 2).sum(dim=2)
            data = (tm * err).sum(dim=1) / (n_train * m)
            penalty = wd * ((learn["W1"] ** 2).sum(dim=(1, 2)) + (learn["W2"] ** 2).sum(dim=(1, 2)))
            loss = (data + penalty).sum()
            opt.zero_grad()
            loss.backward()
            opt.step()
        params = {k: v.numpy().copy() for k, v in {**fixed, **snap}.items()}
    return TrainedNetworks(val_loss=val_loss, predictions=pred.numpy().copy(), params=params)
