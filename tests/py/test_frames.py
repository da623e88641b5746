"""Frame pre-processing and the frame store: the crop/grey step against a hand-made image (the
centre 224 x 224, BT.601 luma rounded — PIL's convert("L") values for pure colours), a store that
keeps labels with frames and writes a case whole (a half-written case is not listed)."""
import numpy as np
import pytest

from pydem.rigs.frames import crop_grey
from pydem.seed001.store import FrameStore, species_masks


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


def test_species_masks_follow_the_renderer_grey_levels():
    """libdem's grey frames as the hopper rig draws them (coarse = material 0, fine = material 2,
    a wall): every fine-band pixel lies on the fine sphere's disk, every coarse-band pixel on the
    coarse one's, none on the wall, and each band covers a steady share of its disk (the shading
    is the same on every sphere, so the share is what ties a pixel count to an area)."""
    import pydem
    d = pydem.Domain(lo=(0, 0, 0), hi=(0.1, 0.02, 0.05), gravity=(0, 0, 0))
    for _ in range(3):
        d.set_pair(m := d.add_material(), m)
    d.add_particles([[0.03, 0.01, 0.025], [0.07, 0.01, 0.025]], [0.012, 0.006], [0, 2])
    d.add_plane_wall(axis=0, side=1, position=0.001, material=0)
    img = crop_grey(d.render(width=420, height=230, view_axis=1, window=((0.0, 0.1), (0.0, 0.05)), color="grey"))
    fine, coarse = species_masks(img[None])[0]
    # the centre crop keeps columns 98..321 of 420: x = 0.0233 .. 0.0767 m; rows 3..226 of 230
    x = 0.0233 + (np.arange(224) + 0.5) / 4200.0
    z = 0.05 - (np.arange(224)[:, None] + 3.5) / 4600.0
    on = lambda cx, r: (x - cx) ** 2 + (z - 0.025) ** 2 <= (r * 1.05) ** 2  # noqa: E731  (a pixel of margin)
    assert fine.any() and coarse.any()
    assert not (fine & ~on(0.07, 0.006)).any() and not (coarse & ~on(0.03, 0.012)).any()
    share = lambda mask, cx, r: mask.sum() / on(cx, r / 1.05).sum()  # noqa: E731
    # closed form: the renderer's shading law over a unit disk gives the bands 0.862 and 0.197 of
    # it; the pixel grid shifts them by about a rim pixel (coarse: a ring of 1 px at r = 50 px is
    # 4 % of the disk, and the coarse band is the rim)
    u = np.linspace(-1, 1, 1001)
    du, dv = np.meshgrid(u, u)
    inside = du ** 2 + dv ** 2 <= 1
    shade = np.minimum(1, 0.45 + 0.55 * np.maximum(0, 0.8 * np.sqrt(np.clip(1 - du ** 2 - dv ** 2, 0, 1))
                                                       - 0.35 * du - 0.35 * dv + 0.2))
    law = lambda grey, band: species_masks(np.rint(grey * shade).astype(np.uint8)[None])[0, band][inside].mean()  # noqa: E731
    assert share(fine, 0.07, 0.006) == pytest.approx(law(110, 0), abs=0.02)
    assert share(coarse, 0.03, 0.012) == pytest.approx(law(70, 1), abs=0.04)
    with pytest.raises(ValueError, match="uint8"):
        species_masks(img.astype(float)[None])


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
    from pydem.seed001.gra import PARAMETERS, gra_tables
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
