"""Decoding statistics: grasp-grouped per-grasp decisions, balanced accuracy, per-class recall,
chance level and the published per-ISI protocol, checked against scikit-learn called directly
on samples built here (not by the module under test)."""

import numpy as np
import pytest
from sklearn.metrics import balanced_accuracy_score, recall_score
from sklearn.model_selection import StratifiedGroupKFold, StratifiedKFold, cross_val_predict
from sklearn.neighbors import KNeighborsClassifier
from sklearn.tree import DecisionTreeClassifier

from cuneate.sim.decode import NO_DECISION, decode_trials

CLASSES = ["a", "b", "c", "d"]
SEED = 3


def _trains(isi_of_trial, n_trials, gratings=2, n_isi=8, rng=None):
    """Spike trains (one per trial x grating) whose ISIs are ``isi_of_trial(t, g)`` plus a
    little jitter; also the samples ``[isi, grating]``, labels and groups built directly."""
    trains, trial, grating = [], [], []
    for t in range(n_trials):
        for g in range(gratings):
            isi = isi_of_trial(t, g) + (rng.uniform(-0.2, 0.2, n_isi) if rng is not None
                                         else np.zeros(n_isi))
            trains.append(np.cumsum(np.r_[1.0, isi]))
            trial.append(t)
            grating.append(g)
    return trains, trial, grating


def _samples(trains, trial, grating, trial_class):
    X, y, groups = [], [], []
    for s, t, g in zip(trains, trial, grating):
        for v in np.diff(s):
            X.append([v, g])
            y.append(trial_class[t])
            groups.append(t)
    return np.array(X), np.array(y), np.array(groups)


def _soft_per_grasp(proba, classes_sorted, groups, n_trials):
    out = np.empty(n_trials, dtype=object)
    for t in range(n_trials):
        out[t] = classes_sorted[np.argmax(proba[groups == t].mean(axis=0))]
    return out


@pytest.fixture(scope="module")
def overlapping():
    """Four classes, six grasps each; ``c`` and ``d`` share their ISI distribution (as ABS and
    aluminium do under the synthetic pad), ``a`` and ``b`` are apart."""
    rng = np.random.default_rng(0)
    trial_class = [CLASSES[t % 4] for t in range(24)]
    centre = {"a": 2.0, "b": 6.0, "c": 12.0, "d": 12.0}
    trains, trial, grating = _trains(lambda t, g: centre[trial_class[t]] + 0.5 * g +
                                     rng.normal(0, 0.8), 24, rng=rng)
    return trains, trial, grating, trial_class


def test_grouped_headline_matches_sklearn(overlapping):
    trains, trial, grating, trial_class = overlapping
    d = decode_trials(trains, trial, grating, trial_class, CLASSES, kind="tree", features="isi",
                      cv_folds=50, max_depth=3, seed=SEED)
    X, y, groups = _samples(trains, trial, grating, trial_class)
    folds = 6                                  # fewest grasps in a class
    model = DecisionTreeClassifier(max_depth=3, random_state=SEED)
    proba = cross_val_predict(model, X, y, groups=groups, method="predict_proba",
                              cv=StratifiedGroupKFold(folds, shuffle=True, random_state=SEED))
    per_grasp = _soft_per_grasp(proba, np.unique(y), groups, 24)
    h = d.headline
    assert h.name.startswith("grasp-grouped, per grasp") and h.folds == folds
    assert h.n_samples == 24 and h.unit == "grasp"
    assert d.accuracy == h.balanced_accuracy == pytest.approx(
        balanced_accuracy_score(trial_class, per_grasp))
    assert h.accuracy == pytest.approx(np.mean(per_grasp == np.array(trial_class)))
    rec = recall_score(trial_class, per_grasp, labels=CLASSES, average=None, zero_division=0)
    assert [h.recall[c] for c in CLASSES] == pytest.approx(list(rec))
    assert h.chance_balanced == 0.25 and h.chance == 0.25
    assert h.confusion.sum() == 24 and np.trace(h.confusion) == round(24 * h.accuracy)
    # a and b separate; c and d cannot both be right
    assert h.recall["a"] == 1.0 and h.recall["b"] == 1.0
    assert h.recall["c"] + h.recall["d"] < 2.0


def test_per_isi_rows_match_sklearn(overlapping):
    trains, trial, grating, trial_class = overlapping
    d = decode_trials(trains, trial, grating, trial_class, CLASSES, kind="tree", features="isi",
                      cv_folds=50, max_depth=3, seed=SEED)
    X, y, groups = _samples(trains, trial, grating, trial_class)
    model = DecisionTreeClassifier(max_depth=3, random_state=SEED)
    proba = cross_val_predict(model, X, y, groups=groups, method="predict_proba",
                              cv=StratifiedGroupKFold(6, shuffle=True, random_state=SEED))
    per_isi = np.unique(y)[np.argmax(proba, axis=1)]
    row = d.row("grasp-grouped, per ISI")
    assert row.n_samples == y.size == 24 * 2 * 8
    assert row.balanced_accuracy == pytest.approx(balanced_accuracy_score(y, per_isi))
    pub = d.row("published")
    k = min(50, min(np.count_nonzero(y == c) for c in CLASSES))
    assert pub.folds == k and "StratifiedKFold" in pub.cv
    pred = cross_val_predict(model, X, y, cv=StratifiedKFold(k, shuffle=True, random_state=SEED))
    assert pub.accuracy == pytest.approx(np.mean(pred == y))
    assert pub.balanced_accuracy == pytest.approx(balanced_accuracy_score(y, pred))
    assert [r.name.split(":")[0] for r in d.rows] == ["grasp-grouped, per grasp",
                                                       "grasp-grouped, per ISI", "published"]


def test_grasp_fingerprints_leak_into_the_published_protocol_only():
    """Each grasp has its own ISI (a fingerprint) unrelated to its class: 1-NN over shuffled
    ISIs finds the grasp and its class every time, grouped cross-validation cannot."""
    rng = np.random.default_rng(1)
    n = 24
    trial_class = [CLASSES[t % 4] for t in range(n)]
    finger = rng.permutation(n) * 3.0 + 5.0
    trains, trial, grating = _trains(lambda t, g: finger[t], n, gratings=1)
    d = decode_trials(trains, trial, grating, trial_class, CLASSES, kind="knn", features="isi",
                      cv_folds=6, neighbours=1, seed=SEED)
    assert d.row("published").accuracy == 1.0
    X, y, groups = _samples(trains, trial, grating, trial_class)
    proba = cross_val_predict(KNeighborsClassifier(1), X, y, groups=groups,
                              method="predict_proba",
                              cv=StratifiedGroupKFold(6, shuffle=True, random_state=SEED))
    per_grasp = _soft_per_grasp(proba, np.unique(y), groups, n)
    assert d.accuracy == pytest.approx(balanced_accuracy_score(trial_class, per_grasp))
    assert d.accuracy < 0.6


def test_grasp_without_spikes_counts_as_wrong_and_majority_vote():
    trial_class = ["a", "b"] * 4
    trains, trial, grating = _trains(lambda t, g: 3.0 if trial_class[t] == "a" else 9.0, 8,
                                     gratings=1, rng=np.random.default_rng(2))
    trains[7] = np.array([5.0])                 # grasp 7 (class b): one spike, no ISI
    for decision in ("soft", "majority"):
        d = decode_trials(trains, trial, grating, trial_class, ["a", "b"], kind="tree",
                          cv_folds=3, seed=SEED, decision=decision)
        h = d.headline
        assert h.recall == {"a": 1.0, "b": 0.75}
        assert h.balanced_accuracy == pytest.approx(0.875)
        assert NO_DECISION in h.labels and h.confusion[h.labels.index("b"), -1] == 1


def test_too_few_grasps_says_why():
    trains, trial, grating = _trains(lambda t, g: 3.0 + t, 2, gratings=1)
    d = decode_trials(trains, trial, grating, ["a", "b"], ["a", "b"], cv_folds=5)
    assert d.accuracy is None and d.rows == [] and "too few" in d.reason


def test_trial_features_and_permutation_chance():
    rng = np.random.default_rng(4)
    trial_class = [CLASSES[t % 4] for t in range(24)]
    centre = {"a": 2.0, "b": 5.0, "c": 9.0, "d": 14.0}
    trains, trial, grating = _trains(lambda t, g: centre[trial_class[t]], 24, rng=rng)
    d = decode_trials(trains, trial, grating, trial_class, CLASSES, kind="tree",
                      features="trial", cv_folds=6, seed=SEED, permutations=20)
    assert [r.name for r in d.rows] == ["grasp-grouped, per grasp"]
    # the features of one grasp, built here: per grating count, mean ISI, CV, latency
    X = []
    for t in range(24):
        row = []
        for s in (trains[2 * t], trains[2 * t + 1]):
            isi = np.diff(s)
            row += [s.size, isi.mean(), isi.std() / isi.mean(), s[0]]
        X.append(row)
    X, y = np.array(X), np.array(trial_class)
    pred = cross_val_predict(DecisionTreeClassifier(max_depth=3, random_state=SEED), X, y,
                             groups=np.arange(24),
                             cv=StratifiedGroupKFold(6, shuffle=True, random_state=SEED))
    h = d.headline
    assert h.balanced_accuracy == pytest.approx(balanced_accuracy_score(y, pred))
    assert h.balanced_accuracy > 0.75
    assert h.null["permutations"] == 20 and h.null["mean"] < 0.5
    assert h.null["p95"] < h.balanced_accuracy and 1 / 21 <= h.null["p_value"] <= 2 / 21


# --------------------------------------------------------------------------- textures
def test_knn_leave_one_out_equals_scikit_learns_pipeline_and_splitters():
    from sklearn.model_selection import LeaveOneGroupOut, LeaveOneOut, cross_val_predict
    from sklearn.neighbors import KNeighborsClassifier
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from cuneate.sim.decode import knn_predict
    rng = np.random.default_rng(3)
    X = rng.normal(size=(50, 3)) * [1.0, 30.0, 0.01] + [0, 5, 0]
    y = rng.integers(0, 4, 50)
    for k in (1, 3):
        ref = cross_val_predict(make_pipeline(StandardScaler(), KNeighborsClassifier(k)), X, y,
                                cv=LeaveOneOut())
        np.testing.assert_array_equal(knn_predict(X, y, k, False), ref)
        D = np.sqrt(((X[:, None] - X[None]) ** 2).sum(-1))
        ref = cross_val_predict(KNeighborsClassifier(k, metric="precomputed"), D, y,
                                cv=LeaveOneOut())
        np.testing.assert_array_equal(knn_predict(D, y, k, True), ref)
    groups = np.arange(50) % 5
    got = knn_predict(D, y, 1, True, groups)
    for g in range(5):                 # each trial's neighbour is from another group
        sel = groups == g
        nearest = np.argmin(np.where(groups[None] == g, np.inf, D[sel]), axis=1)
        np.testing.assert_array_equal(got[sel], y[nearest])
    assert np.array_equal(got, cross_val_predict(KNeighborsClassifier(1, metric="precomputed"),
                                                 D, y, cv=LeaveOneGroupOut(), groups=groups))


def _textures(rng, rates, n=6, t=1000.0):
    """Poisson trains: per class, per channel a rate; ``n`` trials a class."""
    y, trains = [], {f"c{k}": [] for k in range(len(rates[0]))}
    for ci, r in enumerate(rates):
        for _ in range(n):
            y.append(f"t{ci}")
            for k, rk in enumerate(r):
                trains[f"c{k}"].append(np.sort(rng.uniform(0, t, rng.poisson(rk * t / 1e3))))
    return trains, y


def test_texture_decoders_report_every_row_and_never_a_silent_channel_at_chance():
    from cuneate.sim.decode import TEXTURE_DECODERS, confusions, decode_textures
    rng = np.random.default_rng(4)
    trains, y = _textures(rng, [(10, 0), (40, 0), (80, 0)])
    d = decode_textures(trains, y, ["t0", "t1", "t2"], (0.0, 1000.0), 5.0, 1)
    assert not d.reason
    # the silent channel is a row with its reason for every decoder, never a figure
    for dec in TEXTURE_DECODERS:
        r = d.row(dec, "c1")
        assert r.accuracy is None and r.reason == "no spike on this channel"
        assert d.row(dec, "c0").accuracy is not None
    assert d.row("VP", "all channels") is None          # one channel decoded: nothing to pool
    assert d.best("rate").accuracy == 1.0 and d.accuracy == d.channel_range("VP")[0]
    assert [x["trains"] for x in d.vp_timing] == [18] and d.spikes["c1"] == 0
    assert d.to_dict()["best_channel"] == {"rate": "c0", "rate + CV": "c0", "VP": "c0"}
    # two classes of one rate: their confusions are listed
    trains, y = _textures(rng, [(30, 30), (30, 30), (90, 5)], n=8)
    d = decode_textures(trains, y, ["t0", "t1", "t2"], (0.0, 1000.0), 5.0, 1)
    conf = confusions(d.headline.protocol)
    assert {(a, b) for a, b, _ in conf} <= {("t0", "t1"), ("t1", "t0")} and conf
    assert d.headline.protocol.recall["t2"] == 1.0


def test_nothing_to_decode_is_said_not_scored():
    from cuneate.sim.decode import decode_textures
    silent = {"c0": [np.zeros(0)] * 6}
    d = decode_textures(silent, ["a"] * 3 + ["b"] * 3, ["a", "b"], (0.0, 500.0))
    assert d.rows == [] and d.accuracy is None
    assert d.reason == "no afferent spiked in the window 0-500 ms on any of 1 channels: " \
                       "nothing to decode"
    d = decode_textures({"c0": [np.ones(3)] * 3}, ["a", "a", "b"], ["a", "b"], (0.0, 5.0))
    assert d.reason.startswith("too few trials to decode (3 trials, 2 textures, fewest trials "
                               "of a texture 1")
