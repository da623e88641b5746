"""Frame pre-processing and the frame store: the crop/grey step against a hand-made image (the
centre 224 x 224, BT.601 luma rounded — PIL's convert("L") values for pure colours), a store that
keeps labels with frames and writes a case whole (a half-written case is not listed)."""
import numpy as np
import pytest

from pydem.frames import FrameStore, crop_grey


def test_crop_is_centred_and_grey_is_bt601():
    img = np.zeros((230, 420, 3), np.uint8)
    img[:, :, 0] = 255                       # red everywhere ...
    img[3:227, 98:322] = (0, 255, 0)         # ... but green exactly in the centre 224 x 224
    g = crop_grey(img)
    assert g.shape == (224, 224) and g.dtype == np.uint8
    assert np.all(g == 150)                  # round(0.587 * 255) = 150: only the centre was kept
    assert crop_grey(np.full((224, 224, 3), (0, 0, 255), np.uint8))[0, 0] == 29  # round(0.114 * 255)
    assert crop_grey(np.full((230, 420, 3), 255, np.uint8))[0, 0] == 255
    with pytest.raises(ValueError, match="224"):
        crop_grey(np.zeros((100, 420, 3), np.uint8))


def test_store_round_trip_and_whole_cases(tmp_path):
    s = FrameStore(tmp_path / "f.h5")
    frames = np.random.default_rng(0).integers(0, 255, (5, 224, 224), dtype=np.uint8)
    t = np.linspace(0.0, 0.4, 5)
    s.write_case("A-1", frames, t, 1.0, np.linspace(1, 0.6, 5), {"packing": "A"})
    import h5py
    with h5py.File(tmp_path / "f.h5", "a") as f:  # a case killed half-way
        f["frames"].create_group("A-2.partial")
    assert s.cases() == ["A-1"]
    back = s.read_case("A-1")
    assert np.array_equal(back["frames"], frames) and np.allclose(back["remaining_time"], 1.0 - t)
    assert back["packing"] == "A" and back["discharge_time"] == 1.0


def test_a_hopper_run_fills_the_store_and_the_gra_reads_it(tmp_path):
    """The tiny hopper with in-memory frames, stored as a case; the seed-001 GRA over stored
    discharge times (weights sum to 100 %, one row per Table 1 parameter)."""
    from nn.seed001 import PARAMETERS, gra_tables
    from pydem.rigs import RIGS, load
    cls, cfg_cls = RIGS["hopper"]
    res = cls(load(cfg_cls, "tiny", None, ["frame_interval=0.05", "num_threads=1"])).run(seed=1, images=True)
    assert res.images.shape[1:] == (224, 224) and len(res.images) == len(res.series["frame_time"]) >= 3
    assert res.images.std() > 0  # spheres drawn, not a blank frame
    s = FrameStore(tmp_path / "f.h5")
    s.write_case("tiny", res.images, res.series["frame_time"], res.metrics["discharge_time"].value,
                 res.series["frame_nrrp"])
    back = s.read_case("tiny")
    assert np.array_equal(back["frames"], res.images) and back["nrrp"][0] == pytest.approx(1.0)
    times = {"A-1": 1.2, "A-2": 2.0, "A-3": 1.5, "B1-1": 1.1, "B1-2": 1.9}
    tables = gra_tables(times)
    assert set(tables) == {"A", "B1", "all"} and list(tables["all"]) == list(PARAMETERS)
    assert sum(tables["all"].values()) == pytest.approx(100.0)
