"""Decoding object properties from spike trains with scikit-learn, cross-validated.

Two feature sets (scene key ``decoder.features``):

``isi``
    Every inter-spike interval of every afferent in the decoding window is one sample labelled
    with its trial's class (the published grasp analysis: 562 ISI samples, a coarse decision
    tree, 50-fold cross-validation, 79.9 %). Features: the ISI (ms) and the grating it came
    from. ISIs of one trial land in different folds, as in the publication.
``trial``
    One sample per trial: per afferent the spike count, mean ISI, ISI coefficient of variation
    and first-spike latency in the window (missing values as -1).

Classifiers (``decoder.kind``): ``tree`` (:class:`~sklearn.tree.DecisionTreeClassifier`,
``max_depth``) or ``knn`` (:class:`~sklearn.neighbors.KNeighborsClassifier`). Cross-validation:
:class:`~sklearn.model_selection.StratifiedKFold` with ``min(cv_folds, smallest class)`` folds,
shuffled with the scene's seed; the accuracy is the fraction of samples predicted right by
:func:`~sklearn.model_selection.cross_val_predict`, the confusion matrix counts those
predictions (rows: true class).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Decoded", "isi_samples", "trial_features", "decode"]


@dataclass
class Decoded:
    """Cross-validated decoding result."""

    accuracy: float | None
    confusion: np.ndarray
    classes: list
    n_samples: int
    folds: int
    features: str
    kind: str
    reason: str = ""

    def to_dict(self) -> dict:
        return {"accuracy": self.accuracy, "confusion": self.confusion.tolist(),
                "classes": list(self.classes), "n_samples": self.n_samples, "folds": self.folds,
                "features": self.features, "kind": self.kind, "reason": self.reason}


def _window(t, window):
    t = np.asarray(t, dtype=np.float64)
    if window is None:
        return t
    return t[(t >= window[0]) & (t < window[1])]


def isi_samples(spikes_ms, neuron_trial, neuron_grating, trial_class, window=None):
    """``(X, y)``: one row ``[isi_ms, grating]`` per ISI, ``y`` the class of its trial."""
    X, y = [], []
    for i, s in enumerate(spikes_ms):
        isi = np.diff(_window(s, window))
        for v in isi:
            X.append([v, neuron_grating[i]])
            y.append(trial_class[neuron_trial[i]])
    return np.asarray(X, dtype=np.float64).reshape(-1, 2), np.asarray(y)


def trial_features(spikes_ms, neuron_trial, neuron_grating, trial_class, window=None):
    """``(X, y)``: one row per trial, four features per afferent (see the module docstring)."""
    n_trials = len(trial_class)
    per: dict[int, list] = {t: [] for t in range(n_trials)}
    order = sorted(range(len(spikes_ms)), key=lambda i: (neuron_trial[i], neuron_grating[i]))
    for i in order:
        s = _window(spikes_ms[i], window)
        isi = np.diff(s)
        lat = s[0] - (window[0] if window else 0.0) if s.size else -1.0
        per[neuron_trial[i]] += [s.size, isi.mean() if isi.size else -1.0,
                                 isi.std() / isi.mean() if isi.size > 1 else -1.0, lat]
    X = np.asarray([per[t] for t in range(n_trials)], dtype=np.float64)
    return X, np.asarray(trial_class)


def decode(X, y, classes, kind: str = "tree", cv_folds: int = 50, max_depth: int = 3,
           neighbours: int = 3, seed: int = 1, features: str = "isi") -> Decoded:
    """Cross-validated accuracy and confusion matrix of ``kind`` on ``(X, y)``."""
    from sklearn.metrics import confusion_matrix
    from sklearn.model_selection import StratifiedKFold, cross_val_predict
    from sklearn.neighbors import KNeighborsClassifier
    from sklearn.tree import DecisionTreeClassifier
    y = np.asarray(y)
    k = len(classes)
    present = [c for c in classes if np.count_nonzero(y == c)]
    smallest = min((np.count_nonzero(y == c) for c in present), default=0)
    folds = int(min(cv_folds, smallest))
    if len(present) < 2 or folds < 2:
        return Decoded(None, np.zeros((k, k), dtype=int), list(classes), int(y.size), 0,
                       features, kind, reason=f"too few samples to cross-validate ({y.size} "
                                              f"samples, {len(present)} classes with data, "
                                              f"smallest class {smallest})")
    if kind == "tree":
        model = DecisionTreeClassifier(max_depth=max_depth, random_state=seed)
    elif kind == "knn":
        train = y.size - -(-y.size // folds)        # the smallest training fold
        if neighbours > train:
            return Decoded(None, np.zeros((k, k), dtype=int), list(classes), int(y.size), folds,
                           features, kind, reason=f"{neighbours} neighbours, but the smallest "
                                                  f"training fold holds {train} samples")
        model = KNeighborsClassifier(n_neighbors=neighbours)
    else:
        raise ValueError(f"unknown decoder {kind!r}")
    cv = StratifiedKFold(n_splits=folds, shuffle=True, random_state=seed)
    pred = cross_val_predict(model, X, y, cv=cv)
    cm = confusion_matrix(y, pred, labels=list(classes))
    return Decoded(float(np.mean(pred == y)), cm, list(classes), int(y.size), folds, features,
                   kind)
