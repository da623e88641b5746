"""Seed 001's image networks (nn/cnn.py) and their training (nn/training.py) and baselines (pydem/seed001).

The four backbones are torchvision's architectures written again in plain torch: built for
ImageNet (3 channels, 1000 outputs) each must have exactly torchvision's published parameter
count, which pins every layer's shape. Training must lower the loss on frames whose label a
network can read (the dark area of a synthetic frame), resume from its checkpoint bitwise, and
the baselines must recover the known rate / law of synthetic data."""
import math

import numpy as np
import pytest
import torch

from nn import cnn, training
from pydem.seed001 import baselines, frame_data


@pytest.mark.parametrize("name, build, count", [
    ("AlexNet", lambda: cnn.AlexNet(3, 1000), 61_100_840),
    ("VGG-16", lambda: cnn.VGG(16, 3, 1000), 138_357_544),
    ("VGG-19", lambda: cnn.VGG(19, 3, 1000), 143_667_240),
    ("ResNet-50", lambda: cnn.ResNet50(3, 1000), 25_557_032)])
def test_backbones_have_torchvisions_parameter_counts(name, build, count):
    assert cnn.parameter_count(build()) == count, name


@pytest.mark.parametrize("name", sorted(cnn.BACKBONES))
def test_backbones_regress_one_value_from_grey_frames_down_to_their_smallest_input(name):
    m = cnn.BACKBONES[name]().eval()
    with torch.no_grad():
        for size in (m.min_input, 80):
            assert m(torch.rand(2, 1, size, size)).shape == (2, 1)


def test_cnn_lstm_is_the_seeds_architecture():
    m = cnn.CNNLSTM().eval()
    convs = [layer.out_channels for layer in m.cnn if isinstance(layer, torch.nn.Conv2d)]
    assert convs == [32, 64, 128, 25]
    assert [lstm.hidden_size for lstm in m.lstms] == [4, 8, 16, 32]
    assert m.cnn[-2].out_features == 1024
    with torch.no_grad():
        assert m(torch.rand(3, 5, 1, 48, 48)).shape == (3, 5)  # an NRRP per frame of each sequence


def blobs(n: int, size: int = 64, seed: int = 0):
    """Light frames with a dark square whose area fraction is the label."""
    rng = np.random.default_rng(seed)
    x = np.ones((n, 1, size, size), np.float32)
    side = rng.integers(4, size // 2, n)
    for i, s in enumerate(side):
        a, b = rng.integers(0, size - s, 2)
        x[i, 0, a:a + s, b:b + s] = 0.1
    return x, (side.astype(np.float32) / size) ** 2


@pytest.mark.slow
def test_training_lowers_the_loss_and_resumes_bitwise(tmp_path):
    torch.set_num_threads(1)
    x, y = blobs(160)
    xv, yv = blobs(40, seed=1)
    torch.manual_seed(0)  # the initial weights: the caller's
    first = training.fit(cnn.AlexNetFC(), x, y, xv, yv, epochs=6, batch=16, lr=3e-4, seed=2)
    h = first["history"]
    assert h[-1]["loss"] < 0.5 * h[0]["loss"], h
    assert min(e["validation"] for e in h) < 0.5, h  # standardised: 1 is "predicts the mean"
    # a training killed after 2 epochs and resumed from its checkpoint ends where the whole one did
    # (bitwise: a smaller set of frames shows it as well as the whole)
    x, y, xv, yv = x[:48], y[:48], xv[:16], yv[:16]
    torch.manual_seed(0)
    whole = training.fit(cnn.AlexNetFC(), x, y, xv, yv, epochs=3, batch=16, lr=3e-4, seed=2)["history"]
    ck = tmp_path / "fc.pt"
    torch.manual_seed(0)
    training.fit(cnn.AlexNetFC(), x, y, xv, yv, epochs=2, batch=16, lr=3e-4, seed=2, checkpoint=ck)
    resumed = training.fit(cnn.AlexNetFC(), x, y, xv, yv, epochs=3, batch=16, lr=3e-4, seed=2, checkpoint=ck)
    assert resumed["history"] == whole
    with pytest.raises(ValueError, match="another training"):  # other settings: refused, not resumed
        training.fit(cnn.AlexNetFC(), x, y, xv, yv, epochs=3, batch=16, lr=1e-3, seed=2, checkpoint=ck)


def test_scores_by_hand():
    s = frame_data.scores(np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.5, 2.0]))
    assert s["mae"] == pytest.approx(0.5) and s["rmse"] == pytest.approx(math.sqrt(1.25 / 3))
    assert s["r2"] == pytest.approx(1 - 1.25 / 2.0) and s["relative_error"] == pytest.approx((0.25 + 1 / 3) / 3)
    # near the empty end (y below 10 % of its largest) rows count in MAE/RMSE/R^2, not in the relative error
    s = frame_data.scores(np.array([0.01, 1.0]), np.array([0.5, 1.5]))
    assert s["relative_error"] == pytest.approx(0.5) and s["mae"] == pytest.approx(0.495)


def test_constant_rate_baseline_on_a_steady_discharge():
    t = np.linspace(0.0, 2.0, 101)
    nrrp = np.clip(1.0 - 0.6 * t, 0.0, 1.0)  # a steady discharge, empty at t = 5/3 s
    assert np.allclose(baselines.constant_rate_nrrp(t, nrrp), nrrp, atol=1e-12)


def test_fill_level_gauge_recovers_a_cubic_reading_and_stays_in_0_1():
    # the count remaining as a known cubic of the fill level (calibration discharges), read at new
    # fill levels: exact to round-off; beyond the calibration, clipped to [0, 1]
    fill = np.linspace(0.2, 1.0, 50)
    law = lambda f: 0.1 + 0.3 * f + 0.8 * f ** 2 - 0.2 * f ** 3  # noqa: E731
    new = np.array([0.35, 0.5, 0.77])
    assert np.allclose(baselines.fill_level_nrrp(fill, law(fill), new), law(new), atol=1e-12)
    assert baselines.fill_level_nrrp(fill, law(fill), np.array([3.0, 5.0])).tolist() == [1.0, 0.0]  # 2.8, -3.4


def test_species_gauge_recovers_a_two_species_count_and_stays_in_0_1():
    # cases whose remaining count is w f(F) + (1 - w) g(K), each species' count a known cubic
    # of its visible fill: fitted on three cases (w 0.3, 0.6, 0.9), read exactly on a fourth
    rng = np.random.default_rng(3)
    f = lambda v: 0.2 * v + 0.5 * v ** 2 + 0.3 * v ** 3  # noqa: E731
    g = lambda v: 0.9 * v + 0.1 * v ** 3  # noqa: E731
    case = lambda w, n=40: (rng.uniform(0, 1, (n, 2)), w)  # noqa: E731
    law = lambda fill, w: w * f(fill[:, 0]) + (1 - w) * g(fill[:, 1])  # noqa: E731
    train = [case(w) for w in (0.3, 0.6, 0.9)]
    design = np.concatenate([baselines.species_design(fill, w) for fill, w in train])
    counts = np.concatenate([law(fill, w) for fill, w in train])
    new, w = case(0.75)
    assert np.allclose(baselines.species_gauge_nrrp(design, counts, baselines.species_design(new, w)), law(new, w), atol=1e-12)
    assert baselines.species_gauge_nrrp(design, counts, baselines.species_design(np.array([[3.0, 3.0]]), w)).tolist() == [1.0]


def test_fines_count_share_of_a_table1_case():
    # B1-2: 7,596 spheres of 3 and 9 mm, fine volume fraction 0.4 -> a coarse sphere holds 27 fine
    # volumes, so fines are 0.4 x 27 / (0.4 x 27 + 0.6) = 0.947 of the count
    assert baselines.fines_count_share("B1-2") == pytest.approx(0.4 * 27 / (0.4 * 27 + 0.6), abs=1 / 7596)


def test_species_frames_are_one_grey_frame_per_species():
    # a frame half fine-grey (100), a quarter coarse-grey (45), a quarter wall (40) and background
    frame = np.full((1, 8, 8), 255, np.uint8)
    frame[0, :4] = 100
    frame[0, 4:6] = 45
    frame[0, 6:, :4] = 40
    x = frame_data.species_frames(frame, 8)
    assert x.shape == (1, 2, 8, 8) and x.dtype == np.float32
    assert x[0, 0, :4].max() == 0.0 and x[0, 0, 4:].min() == 1.0   # fine channel: dark where fines are
    assert x[0, 1, 4:6].max() == 0.0 and x[0, 1, 6:].min() == 1.0 and x[0, 1, :4].min() == 1.0
    assert frame_data.species_frames(frame, 2)[0, 0].tolist() == [[0.0, 0.0], [1.0, 1.0]]  # area-averaged


def test_beverloo_baseline_recovers_its_law():
    from pydem.rigs.hopper import TABLE1
    c_true, k_true = 0.58, 1.4
    attrs = {c: {"case": c} for c in TABLE1}
    truth = {}
    for c, a in attrs.items():
        m, d, rho = baselines.case_mass_and_size(a)
        truth[c] = m / (c_true * rho * math.sqrt(9.81) * 0.04 * (0.054 - k_true * d) ** 1.5)
    c, k, predict = baselines.beverloo_discharge({c: truth[c] for c in list(TABLE1)[:15]}, attrs)
    assert c == pytest.approx(c_true, rel=1e-2) and k == pytest.approx(k_true, abs=0.011)  # k on a 0.01 grid
    assert all(predict(attrs[c]) == pytest.approx(truth[c], rel=0.02) for c in list(TABLE1)[15:])


def test_windows_for_the_sequence_model():
    x = np.arange(6, dtype=np.float32).reshape(6, 1, 1, 1)
    w, y = training.windows(x, np.arange(6.0), 4)
    assert w.shape == (3, 4, 1, 1, 1) and y.tolist() == [[0, 1, 2, 3], [1, 2, 3, 4], [2, 3, 4, 5]]


def test_a_time_budget_stops_training_after_the_epoch_that_spends_it_and_a_rerun_goes_on(tmp_path):
    torch.set_num_threads(1)
    x, y = blobs(32)
    xv, yv = blobs(8, seed=1)
    ck = tmp_path / "fc.pt"
    torch.manual_seed(0)
    short = training.fit(cnn.AlexNetFC(), x, y, xv, yv, epochs=4, batch=16, seed=2, checkpoint=ck, time_budget=0.0)
    assert [e["epoch"] for e in short["history"]] == [1]
    torch.manual_seed(0)
    rest = training.fit(cnn.AlexNetFC(), x, y, xv, yv, epochs=4, batch=16, seed=2, checkpoint=ck)
    assert [e["epoch"] for e in rest["history"]] == [1, 2, 3, 4]


def test_the_device_is_the_gpu_only_when_there_is_one():
    assert training.pick_device("cpu").type == "cpu"
    assert training.pick_device("auto").type == ("cuda" if torch.cuda.is_available() else "cpu")
    with pytest.raises(ValueError, match="device"):
        training.pick_device("tpu")
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="no GPU"):
            training.pick_device("cuda")
