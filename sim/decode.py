"""Decoding object properties from spike trains with scikit-learn: what the system decides per
grasp, cross-validated so that no grasp is ever in its own training set; and the texture
experiment's decoders (rate, rate + CV, Victor-Purpura by kNN under leave-one-out, the
spatial VP across conditions: :func:`decode_textures`, :func:`decode_conditions`).

Samples (scene key ``decoder.features``):

``isi``
    Every inter-spike interval of every afferent in the decoding window is one sample
    ``[isi_ms, grating]`` labelled with its grasp's class (the published analysis).
``trial``
    One sample per grasp: per afferent the spike count, mean ISI, ISI coefficient of variation
    and first-spike latency in the window (missing values as -1).

Classifier (``decoder.kind``): ``tree`` (:class:`~sklearn.tree.DecisionTreeClassifier`,
``max_depth``) or ``knn`` (:class:`~sklearn.neighbors.KNeighborsClassifier`).

Protocols, one row each in the report (:class:`Protocol`):

1. **grasp-grouped, per grasp** (the headline): :class:`~sklearn.model_selection.StratifiedGroupKFold`
   with the grasps as groups (``min(cv_folds, grasps of the smallest class)`` folds, shuffled
   with the scene's seed), so every sample of a grasp is predicted by a model that never saw
   that grasp. Each grasp's decision pools its samples (``decoder.decision``: ``soft`` - the
   class of highest mean predicted probability; ``majority`` - the most predicted class, ties
   to the higher mean probability); a grasp without samples (no ISI) has no decision and
   counts as wrong. Balanced accuracy (mean per-class recall, chance ``1/classes``), per-class
   recall and the confusion matrix over grasps.
2. **grasp-grouped, per ISI** (``isi`` features): the same folds, scored per sample.
3. **published: per ISI, shuffled k-fold** (``isi`` features): the published protocol,
   :class:`~sklearn.model_selection.StratifiedKFold` over ISIs with ``min(cv_folds, smallest
   class)`` folds, so ISIs of one grasp sit in training and test folds; kept as a labelled row
   to compare with the publication (its accuracy favours the classes that spike most: the
   chance of always answering the largest class is given beside it).

Scores are scikit-learn's (:func:`~sklearn.metrics.balanced_accuracy_score`,
:func:`~sklearn.metrics.recall_score`, :func:`~sklearn.metrics.confusion_matrix`,
:func:`~sklearn.metrics.classification_report`). With ``decoder.permutations`` = n > 0 the
headline also gets an empirical chance level: the grasps' labels are permuted n times (seeded)
and the whole grouped protocol rerun; the null's mean, 95th percentile and the p-value
``(1 + #{null >= observed}) / (n + 1)``.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..golden.metrics import victor_purpura_matrix

__all__ = ["Decoded", "Protocol", "isi_samples", "trial_features", "decode_trials",
           "NO_DECISION", "decoded_neurons", "TEXTURE_DECODERS", "ALL_CHANNELS", "TextureRow",
           "TextureDecoding", "confusions", "rate_cv", "vp_matrix", "knn_predict",
           "loo_scaled_distances",
           "decode_textures", "decode_conditions"]

#: The predicted label of a grasp with no sample to decide on.
NO_DECISION = "(no spikes)"


@dataclass
class Protocol:
    """One cross-validation protocol's scores (a row of the report)."""

    name: str
    unit: str                 # what one decision is about: "grasp" or "ISI"
    cv: str                   # the splitter, in words
    folds: int
    n_samples: int            # decisions scored
    accuracy: float
    balanced_accuracy: float
    chance: float             # plain accuracy of always answering the largest class
    chance_balanced: float    # 1 / classes with samples
    recall: dict              # class -> recall (None: no sample of that class)
    labels: list              # confusion matrix rows (true) and columns (predicted)
    confusion: np.ndarray
    report: dict              # sklearn's classification_report(output_dict=True)
    report_text: str = ""     # the same, as sklearn prints it
    null: dict | None = None  # the permutation test, when asked for

    def to_dict(self) -> dict:
        return {"name": self.name, "unit": self.unit, "cv": self.cv, "folds": self.folds,
                "n_samples": self.n_samples, "accuracy": self.accuracy,
                "balanced_accuracy": self.balanced_accuracy, "chance": self.chance,
                "chance_balanced": self.chance_balanced, "recall": self.recall,
                "labels": list(self.labels), "confusion": self.confusion.tolist(),
                "classification_report": self.report, "null": self.null}


@dataclass
class Decoded:
    """One engine's decoding: the protocols' rows, the headline first."""

    classes: list
    features: str
    kind: str
    decision: str
    rows: list = field(default_factory=list)
    n_samples: int = 0
    reason: str = ""
    noun: str = "grasp"       # what one trial is: grasp, slide, pulse, recording

    @property
    def headline(self) -> Protocol | None:
        return self.rows[0] if self.rows else None

    @property
    def accuracy(self) -> float | None:
        """The headline figure: balanced accuracy of the grasp-grouped per-grasp decision."""
        return None if not self.rows else self.rows[0].balanced_accuracy

    def row(self, name_start: str) -> Protocol | None:
        """The row whose name starts with ``name_start``."""
        return next((r for r in self.rows if r.name.startswith(name_start)), None)

    def to_dict(self) -> dict:
        return {"headline": f"balanced accuracy of the per-{self.noun} decision, "
                            f"{self.noun}-grouped cross-validation",
                "balanced_accuracy": self.accuracy, "classes": list(self.classes),
                "features": self.features, "kind": self.kind, "decision": self.decision,
                "n_samples": self.n_samples, "reason": self.reason,
                "protocols": [r.to_dict() for r in self.rows]}


def _window(t, window):
    t = np.asarray(t, dtype=np.float64)
    if window is None:
        return t
    return t[(t >= window[0]) & (t < window[1])]


def isi_samples(spikes_ms, neuron_trial, neuron_grating, trial_class, window=None):
    """``(X, y, groups)``: one row ``[isi_ms, grating]`` per ISI, ``y`` the class of its grasp,
    ``groups`` the grasp (trial index)."""
    X, y, g = [], [], []
    for i, s in enumerate(spikes_ms):
        isi = np.diff(_window(s, window))
        t = neuron_trial[i]
        X += [[v, neuron_grating[i]] for v in isi]
        y += [trial_class[t]] * isi.size
        g += [t] * isi.size
    return (np.asarray(X, dtype=np.float64).reshape(-1, 2), np.asarray(y),
            np.asarray(g, dtype=np.int64))


def trial_features(spikes_ms, neuron_trial, neuron_grating, trial_class, window=None):
    """``(X, y, groups)``: one row per grasp, four features per afferent (see the module
    docstring); ``groups`` is the grasp itself."""
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
    return X, np.asarray(trial_class), np.arange(n_trials)


def _model(kind: str, max_depth: int, neighbours: int, seed: int, n: int):
    from sklearn.neighbors import KNeighborsClassifier
    from sklearn.tree import DecisionTreeClassifier
    if kind == "tree":
        return DecisionTreeClassifier(max_depth=max_depth, random_state=seed)
    if kind == "knn":
        return KNeighborsClassifier(n_neighbors=max(1, min(neighbours, n - 1)))
    raise ValueError(f"unknown decoder {kind!r}")


def _protocol(name, unit, cv, folds, y_true, y_pred, classes) -> Protocol:
    from sklearn.metrics import (balanced_accuracy_score, classification_report,
                                 confusion_matrix, recall_score)
    y_true, y_pred = np.asarray(y_true), np.asarray(y_pred)
    present = [c for c in classes if np.any(y_true == c)]
    labels = list(classes) + ([NO_DECISION] if np.any(y_pred == NO_DECISION) else [])
    rec = recall_score(y_true, y_pred, labels=present, average=None, zero_division=0)
    counts = [int(np.count_nonzero(y_true == c)) for c in present]
    with warnings.catch_warnings():       # a grasp without a decision is a wrong answer
        warnings.filterwarnings("ignore", "y_pred contains classes not in y_true")
        bal = float(balanced_accuracy_score(y_true, y_pred))
    return Protocol(
        name, unit, cv, folds, int(y_true.size), float(np.mean(y_true == y_pred)), bal,
        max(counts) / y_true.size, 1.0 / len(present),
        {c: (float(rec[present.index(c)]) if c in present else None) for c in classes},
        labels, confusion_matrix(y_true, y_pred, labels=labels),
        classification_report(y_true, y_pred, labels=present, output_dict=True,
                              zero_division=0),
        classification_report(y_true, y_pred, labels=present, zero_division=0))


def _grouped_decisions(model, X, y, groups, n_trials, folds, seed, decision):
    """Per-sample and per-grasp predictions of the grasp-grouped protocol."""
    from sklearn.model_selection import StratifiedGroupKFold, cross_val_predict
    cv = StratifiedGroupKFold(n_splits=folds, shuffle=True, random_state=seed)
    proba = cross_val_predict(model, X, y, cv=cv, groups=groups, method="predict_proba")
    order = np.unique(y)                      # the columns of predict_proba
    per_sample = order[np.argmax(proba, axis=1)]
    per_grasp = np.full(n_trials, NO_DECISION, dtype=object)
    for t in np.unique(groups):
        sel = groups == t
        mean = proba[sel].mean(axis=0)
        if decision == "majority":
            votes = np.bincount(np.argmax(proba[sel], axis=1), minlength=order.size)
            best = np.flatnonzero(votes == votes.max())
            per_grasp[t] = order[best[np.argmax(mean[best])]]
        else:
            per_grasp[t] = order[np.argmax(mean)]
    return per_sample, per_grasp


def decode_trials(spikes_ms, neuron_trial, neuron_grating, trial_class, classes,
                  kind: str = "tree", features: str = "isi", cv_folds: int = 50,
                  max_depth: int = 3, neighbours: int = 3, seed: int = 1, window=None,
                  decision: str = "soft", permutations: int = 0,
                  noun: str = "grasp") -> Decoded:
    """Decode the grasps' classes from their spike trains with every protocol of the module
    docstring; returns a :class:`Decoded` (its ``reason`` says why when it cannot decode).
    ``noun``: what one trial is (a grasp; a slide, a pulse, a recording), in the rows' names
    and the reasons."""
    from sklearn.model_selection import StratifiedKFold, cross_val_predict
    fn = isi_samples if features == "isi" else trial_features
    X, y, groups = fn(spikes_ms, neuron_trial, neuron_grating, trial_class, window)
    trial_class = np.asarray(trial_class, dtype=object)
    out = Decoded(list(classes), features, kind, decision, n_samples=int(y.size), noun=noun)
    present = [c for c in classes if np.any(y == c)]
    grasps = {c: np.unique(groups[y == c]).size for c in present}
    folds = int(min([cv_folds, *grasps.values()])) if grasps else 0
    if len(present) < 2 or folds < 2:
        out.reason = (f"too few samples to cross-validate ({y.size} samples, {len(present)} "
                      f"classes with data, fewest {noun}s with samples in a class "
                      f"{min(grasps.values(), default=0)})")
        return out
    train = y.size - -(-y.size // folds)            # the smallest training fold (samples)
    if kind == "knn" and neighbours > train:
        out.reason = (f"{neighbours} neighbours, but the smallest training fold holds {train} "
                      f"samples")
        return out
    model = _model(kind, max_depth, neighbours, seed, y.size)
    per_sample, per_grasp = _grouped_decisions(model, X, y, groups, trial_class.size, folds,
                                               seed, decision)
    grouped_cv = f"StratifiedGroupKFold, {folds} folds on {noun}s"
    head = _protocol(f"{noun}-grouped, per {noun}", noun, grouped_cv, folds, trial_class,
                     per_grasp, classes)
    out.rows.append(head)
    if features == "isi":
        out.rows.append(_protocol(f"{noun}-grouped, per ISI", "ISI", grouped_cv, folds, y,
                                  per_sample, classes))
        smallest = min(int(np.count_nonzero(y == c)) for c in present)
        k = int(min(cv_folds, smallest))
        cv = StratifiedKFold(n_splits=k, shuffle=True, random_state=seed)
        pred = cross_val_predict(model, X, y, cv=cv)
        out.rows.append(_protocol("published: per ISI, shuffled k-fold", "ISI",
                                  f"StratifiedKFold, {k} folds on ISIs, shuffled", k, y, pred,
                                  classes))
    if permutations > 0:
        rng = np.random.default_rng(seed)
        null = []
        for _ in range(int(permutations)):
            perm = rng.permutation(trial_class)
            _, pg = _grouped_decisions(model, X, perm[groups], groups, trial_class.size, folds,
                                       seed, decision)
            null.append(_protocol("", noun, "", folds, perm, pg, classes).balanced_accuracy)
        null = np.asarray(null)
        head.null = {"permutations": int(permutations), "mean": float(null.mean()),
                     "p95": float(np.percentile(null, 95)),
                     "p_value": float((1 + np.count_nonzero(null >= head.balanced_accuracy))
                                      / (null.size + 1))}
    return out


def decoded_neurons(population: str, spikes_ms, neurons, layer: dict, engine: str):
    """``(trains, trial, index)``: the spike trains a scene's decoder reads (``decoder
    .population``) and each one's trial and index within it: every afferent (``""``), one
    afferent population's (``neurons``: the scene's afferent table), or the cuneate layer's
    (``layer``: its population, ``trial``, ``index`` and ``spikes`` by engine)."""
    if not population:
        return spikes_ms, neurons.trial, neurons.grating
    if layer and population == layer["population"]:
        return layer["spikes"][engine], layer["trial"], layer["index"]
    keep = [i for i, p in enumerate(neurons.population) if p == population]
    return ([spikes_ms[i] for i in keep], [neurons.trial[i] for i in keep],
            [neurons.grating[i] for i in keep])


# --------------------------------------------------------------------------- textures
# The texture experiment's decoders (the seeds'): each texture trial decided from one
# channel's spike train (or from every channel's) by k nearest neighbours under leave-one-out,
# on the spike rate, on the rate and the ISIs' coefficient of variation (features scaled on
# the training trials), or on Victor-Purpura distances (Victor & Purpura 1996; q = 5/s by
# default) - and the spatial VP: spike times within the slide rescaled by the trial's
# velocity into positions, the cost then per mm.

#: The texture decoders, in the report's order.
TEXTURE_DECODERS = ("rate", "rate + CV", "VP")
#: The name of the rows that pool every channel.
ALL_CHANNELS = "all channels"


@dataclass
class TextureRow:
    """One decoder on one channel (or every channel): its leave-one-out scores, or why it
    did not decode."""

    decoder: str
    channel: str
    protocol: Protocol | None
    reason: str = ""

    @property
    def accuracy(self) -> float | None:
        return None if self.protocol is None else self.protocol.balanced_accuracy

    def to_dict(self) -> dict:
        return {"decoder": self.decoder, "channel": self.channel, "reason": self.reason,
                "balanced_accuracy": self.accuracy,
                "scores": None if self.protocol is None else self.protocol.to_dict()}


@dataclass
class TextureDecoding:
    """Every texture decoder on every channel of one engine's trains (:func:`decode_textures`).
    ``best[decoder]`` is the channel decoding best with it, chosen on these same trials as the
    seeds report it; the rows pooling every channel involve no such choice."""

    classes: list
    channels: list
    rows: list = field(default_factory=list)
    neighbours: int = 1
    q_per_s: float = 5.0
    window_ms: tuple = (0.0, 0.0)
    reason: str = ""
    spikes: dict = field(default_factory=dict)        # channel -> spikes in the window
    no_cv: dict = field(default_factory=dict)         # channel -> trials with < 3 spikes
    vp_timing: list = field(default_factory=list)     # one entry per matrix
    matrices: dict = field(default_factory=dict)      # channel -> VP matrix (figures)

    def row(self, decoder: str, channel: str) -> TextureRow | None:
        return next((r for r in self.rows if r.decoder == decoder and r.channel == channel),
                    None)

    def best(self, decoder: str) -> TextureRow | None:
        """The single channel decoding best with ``decoder`` (the first of equals)."""
        rows = [r for r in self.rows if r.decoder == decoder and r.channel != ALL_CHANNELS
                and r.accuracy is not None]
        return max(rows, key=lambda r: r.accuracy) if rows else None

    def channel_range(self, decoder: str) -> tuple | None:
        """``(mean, lowest, highest)`` balanced accuracy of ``decoder`` over the single
        channels that decoded, each alone (the seeds' per-channel figures)."""
        acc = [r.accuracy for r in self.rows if r.decoder == decoder
               and r.channel != ALL_CHANNELS and r.accuracy is not None]
        return (float(np.mean(acc)), min(acc), max(acc)) if acc else None

    @property
    def headline(self) -> TextureRow | None:
        """VP and kNN on the best channel (whose confusions and matrix the report shows)."""
        return self.best("VP")

    @property
    def accuracy(self) -> float | None:
        """The headline figure: VP + kNN's balanced accuracy averaged over the channels, each
        decoded alone (no channel chosen on the results)."""
        r = self.channel_range("VP")
        return None if r is None else r[0]

    def to_dict(self) -> dict:
        return {"headline": "balanced accuracy of VP + kNN (leave-one-out), mean over the "
                            "channels each decoded alone",
                "balanced_accuracy": self.accuracy, "classes": list(self.classes),
                "per_channel": {d: (dict(zip(("mean", "lowest", "highest"), r))
                                    if (r := self.channel_range(d)) else None)
                                for d in TEXTURE_DECODERS},
                "channels": list(self.channels), "neighbours": self.neighbours,
                "q_per_s": self.q_per_s, "window_ms": list(self.window_ms),
                "reason": self.reason, "spikes": self.spikes, "trials_without_cv": self.no_cv,
                "best_channel": {d: (b.channel if (b := self.best(d)) else None)
                                 for d in TEXTURE_DECODERS},
                "vp_timing": self.vp_timing, "rows": [r.to_dict() for r in self.rows]}


def confusions(p: Protocol) -> list[tuple[str, str, int]]:
    """The off-diagonal entries of a protocol's confusion matrix, ``(true, predicted,
    count)``, most frequent first."""
    out = [(str(t), str(q), int(p.confusion[i, j])) for i, t in enumerate(p.labels)
           for j, q in enumerate(p.labels) if i != j and p.confusion[i, j]]
    return sorted(out, key=lambda x: -x[2])


def rate_cv(trains, window_ms) -> tuple[np.ndarray, np.ndarray]:
    """Per train: the rate (Hz) and the ISIs' coefficient of variation (0 below three spikes)
    within ``window_ms``."""
    dur_s = (window_ms[1] - window_ms[0]) / 1000.0
    rate, cv = [], []
    for s in trains:
        s = _window(s, window_ms)
        rate.append(s.size / dur_s)
        isi = np.diff(s)
        cv.append(float(isi.std() / isi.mean()) if isi.size >= 2 and isi.mean() > 0 else 0.0)
    return np.asarray(rate), np.asarray(cv)


def vp_matrix(trains, q_per_ms: float, timing: list | None = None, what: str = "") -> np.ndarray:
    """The Victor-Purpura matrix of ``trains`` (:func:`~cuneate.golden.metrics
    .victor_purpura_matrix`); ``timing`` gets one entry: trains, spikes, seconds."""
    t0 = time.perf_counter()
    D = victor_purpura_matrix(trains, q_per_ms)
    if timing is not None:
        timing.append({"what": what, "trains": len(trains),
                       "spikes": int(sum(len(t) for t in trains)),
                       "seconds": time.perf_counter() - t0})
    return D


def loo_scaled_distances(X) -> np.ndarray:
    """``D[i, j]``: the Euclidean distance from trial ``i`` to trial ``j`` with the features
    standardized (scikit-learn's :class:`~sklearn.preprocessing.StandardScaler`: mean and
    population standard deviation, a constant feature left unscaled) on every trial but ``i``:
    what a pipeline scaling on the training set gives each left-out trial."""
    X = np.asarray(X, dtype=np.float64).reshape(len(X), -1)
    n = X.shape[0]
    m = (X.sum(axis=0)[None] - X) / (n - 1)
    var = ((X ** 2).sum(axis=0)[None] - X ** 2) / (n - 1) - m ** 2
    sd = np.sqrt(np.maximum(var, 0.0))
    sd[sd <= 1e-12 * np.maximum(1.0, np.abs(m))] = 1.0
    diff = (X[:, None, :] - X[None, :, :]) / sd[:, None, :]
    return np.sqrt((diff ** 2).sum(axis=-1))


def knn_predict(X, y, neighbours: int, precomputed: bool, groups=None) -> np.ndarray:
    """Leave-one-out predictions of k nearest neighbours (scikit-learn's
    :class:`~sklearn.neighbors.KNeighborsClassifier`): on a precomputed distance matrix, or on
    features standardized on each training set (:func:`loo_scaled_distances`). Leave-one-out
    asks the fitted classifier for every trial's neighbours among the others
    (``predict(None)``). With ``groups`` (a condition per trial): leave one group out
    instead, each trial decided by the other groups' trials only."""
    from sklearn.model_selection import LeaveOneGroupOut, cross_val_predict
    from sklearn.neighbors import KNeighborsClassifier
    y = np.asarray(y)
    D = np.asarray(X, dtype=np.float64) if precomputed else loo_scaled_distances(X)
    # the smallest training set: all trials but one, or but the largest group
    train = y.size - (1 if groups is None else max(np.unique(groups, return_counts=True)[1]))
    knn = KNeighborsClassifier(n_neighbors=max(1, min(int(neighbours), train)),
                               metric="precomputed")
    if groups is None:
        return knn.fit(D, y).predict(None)
    if not precomputed:
        raise ValueError("leave one group out decodes precomputed distances")
    return cross_val_predict(knn, D, y, cv=LeaveOneGroupOut(), groups=groups)


def decode_textures(trains: dict, trial_class, classes, window_ms, q_per_s: float = 5.0,
                    neighbours: int = 1) -> TextureDecoding:
    """Decode each trial's texture from its spike trains. ``trains``: channel name -> one train
    per trial (ms); ``window_ms``: the spikes decoded. Rows: every decoder of
    :data:`TEXTURE_DECODERS` on every channel and on all channels together (rates and CVs as
    one feature vector; VP distances summed over the channels). A channel that never spikes is
    a row with its reason, never a chance-level figure; with no spike at all the decoding says
    so and has no rows."""
    y = np.asarray(trial_class, dtype=object)
    out = TextureDecoding(list(classes), list(trains), neighbours=int(neighbours),
                          q_per_s=float(q_per_s), window_ms=tuple(window_ms))
    counts = {c: int(sum(_window(s, window_ms).size for s in tr)) for c, tr in trains.items()}
    out.spikes = counts
    present = [c for c in classes if np.any(y == c)]
    per_class = min((int(np.count_nonzero(y == c)) for c in present), default=0)
    if len(present) < 2 or per_class < 2:
        out.reason = (f"too few trials to decode ({y.size} trials, {len(present)} textures, "
                      f"fewest trials of a texture {per_class}; leave-one-out needs two of each)")
        return out
    if not any(counts.values()):
        out.reason = (f"no afferent spiked in the window {window_ms[0]:g}-{window_ms[1]:g} ms "
                      f"on any of {len(trains)} channels: nothing to decode")
        return out
    q = q_per_s / 1000.0
    vp_matrix([np.zeros(0), np.ones(1)], q)     # the compiled kernel loaded before timing it
    feats, mats = {}, {}
    for ch, tr in trains.items():
        w = [_window(s, window_ms) for s in tr]
        rate, cv = rate_cv(w, window_ms)
        out.no_cv[ch] = int(sum(len(s) < 3 for s in w))
        if not counts[ch]:
            for d in TEXTURE_DECODERS:
                out.rows.append(TextureRow(d, ch, None, "no spike on this channel"))
            continue
        feats[ch] = (rate, cv)
        mats[ch] = vp_matrix(w, q, out.vp_timing, ch)
        out.matrices[ch] = mats[ch]
    channels = [c for c in trains if c in feats]
    sets = [(c, [c]) for c in channels] + ([(ALL_CHANNELS, channels)] if len(channels) > 1
                                            else [])
    for name, chs in sets:
        X_rate = np.column_stack([feats[c][0] for c in chs])
        X_cv = np.column_stack([x for c in chs for x in feats[c]])
        D = sum(mats[c] for c in chs)
        for d, X, pre in (("rate", X_rate, False), ("rate + CV", X_cv, False),
                          ("VP", D, True)):
            pred = knn_predict(X, y, neighbours, pre)
            out.rows.append(TextureRow(d, name, _protocol(
                f"{d}, {name}", "trial", "leave-one-out", y.size, y, pred, classes)))
    return out


def decode_conditions(trains: dict, trial_class, classes, condition, q: float,
                      neighbours: int = 1) -> list[dict]:
    """VP + kNN over trials of several sensing conditions (``condition``: one label per
    trial), on ``trains`` (channel -> one train per trial, in ms or in mm; ``q`` per ms or per
    mm): leave one trial out with every condition in the references (pooled), and leave one
    condition out (each trial decided by the other conditions' trials alone). Returns one row
    per channel (and all channels) and protocol: balanced accuracy and per-class recall."""
    y = np.asarray(trial_class, dtype=object)
    mats = {c: vp_matrix(tr, q) for c, tr in trains.items()}
    sets = [(c, [c]) for c in trains] + ([(ALL_CHANNELS, list(trains))] if len(trains) > 1
                                          else [])
    rows = []
    for name, chs in sets:
        D = sum(mats[c] for c in chs)
        for proto, groups in (("pooled, leave one trial out", None),
                              ("leave one condition out", np.asarray(condition))):
            pred = knn_predict(D, y, neighbours, True, groups)
            p = _protocol(f"VP, {name}", "trial", proto, y.size, y, pred, classes)
            rows.append({"channel": name, "protocol": proto,
                         "balanced_accuracy": p.balanced_accuracy, "recall": p.recall,
                         "chance": p.chance_balanced})
    return rows
