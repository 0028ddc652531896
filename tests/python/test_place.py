"""Place recognition from Python: vocabulary training and files, the keyframe database, the
``slslam vocab`` command and the vocabulary shipped with the package."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import slslam
from slslam import _core
from slslam.cli import main
from slslam.errors import InputError
from slslam.place import (
    KeyframeDatabase,
    Vocabulary,
    VocabularyError,
    VocabularyOptions,
    default_vocabulary_path,
)


def clustered_images(
    rng: np.random.Generator, dtype: type, cols: int, images: int = 12, clusters: int = 16
) -> tuple[list[np.ndarray], np.ndarray]:
    """Images of noisy members of random cluster centres (binary: a few flipped bits)."""
    if dtype == np.uint8:
        centres = rng.integers(0, 256, size=(clusters, cols), dtype=np.uint8)
    else:
        centres = rng.uniform(0, 10, size=(clusters, cols)).astype(np.float32)
    out = []
    for i in range(images):
        chosen = np.arange(i, i + 5) % clusters
        rows = np.repeat(centres[chosen], 6, axis=0)
        if dtype == np.uint8:
            flips = rng.integers(0, 8, size=rows.shape) == 0
            rows = rows ^ (flips.astype(np.uint8) << rng.integers(0, 8, size=rows.shape)).astype(
                np.uint8
            )
        else:
            rows = (rows + rng.normal(0, 0.05, size=rows.shape)).astype(np.float32)
        out.append(np.ascontiguousarray(rows))
    return out, centres


@pytest.mark.parametrize(("dtype", "cols"), [(np.uint8, 32), (np.float32, 24)])
def test_train_save_load_transform_round_trip(tmp_path, dtype, cols):
    rng = np.random.default_rng(1)
    images, _ = clustered_images(rng, dtype, cols)
    vocabulary = Vocabulary.train(images, VocabularyOptions(branching=4, levels=2, seed=3))
    assert vocabulary.descriptor_type == ("binary" if dtype == np.uint8 else "float")
    assert vocabulary.descriptor_cols == cols
    assert 4 < vocabulary.num_words <= 16

    path = vocabulary.save(tmp_path / "v.slvoc")
    assert not (tmp_path / "v.slvoc.partial").exists()
    loaded = Vocabulary.load(path)
    assert loaded.num_words == vocabulary.num_words
    for image in images[:4]:
        bow = vocabulary.transform(image)
        assert bow == loaded.transform(image)
        assert sum(bow.values()) == pytest.approx(1.0)
        assert Vocabulary.score(bow, bow) == pytest.approx(1.0)
        bow_again, features = loaded.transform_with_features(image, levels_up=1)
        assert bow_again == bow
        assert sorted(i for rows in features.values() for i in rows) == list(range(len(image)))
    # Images without a common cluster share no word.
    assert Vocabulary.score(vocabulary.transform(images[0]), vocabulary.transform(images[8])) < 0.2


def test_training_and_transform_reject_bad_descriptors():
    rng = np.random.default_rng(2)
    binary = rng.integers(0, 256, size=(50, 32), dtype=np.uint8)
    with pytest.raises(ValueError, match="float32"):
        Vocabulary.train([binary, rng.normal(size=(50, 32)).astype(np.float32)])
    with pytest.raises(ValueError):
        Vocabulary.train([binary.astype(np.int32)])
    vocabulary = Vocabulary.train([binary], VocabularyOptions(branching=3, levels=2))
    with pytest.raises(ValueError, match="CV_32F"):
        vocabulary.transform(np.zeros((3, 32), np.float32))
    with pytest.raises(ValueError, match="x 16"):
        vocabulary.transform(np.zeros((3, 16), np.uint8))
    with pytest.raises(ValueError, match="branching"):
        VocabularyOptions(branching=1).to_core()


def test_keyframe_database_finds_the_revisited_keyframe():
    rng = np.random.default_rng(4)
    images, centres = clustered_images(rng, np.uint8, 32, images=16, clusters=16)
    vocabulary = Vocabulary.train(images, VocabularyOptions(branching=16, levels=1))
    database = KeyframeDatabase()
    for i, image in enumerate(images):
        database.add(i, vocabulary.transform(image))
    assert len(database) == 16
    query = vocabulary.transform(np.repeat(centres[[7, 8, 9, 10, 11]], 3, axis=0))
    best = database.query(query, max_results=3)
    assert best[0].keyframe_id == 7
    assert best[0].score == pytest.approx(1.0)
    others = database.query(query, max_results=3, accept=lambda kf: kf != 7)
    assert others and all(c.keyframe_id != 7 for c in others)
    database.remove(7)
    assert 7 not in database
    assert all(c.keyframe_id != 7 for c in database.query(query, max_results=0))


def textured_image(rng: np.random.Generator, height: int = 240, width: int = 320) -> np.ndarray:
    """A gray image with random rectangles, discs and noise: corners for ORB, made on the spot."""
    image = np.full((height, width), 90.0)
    rows, cols = np.mgrid[0:height, 0:width]
    for _ in range(40):
        x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
        shade = float(rng.integers(0, 256))
        if rng.random() < 0.5:
            w, h = int(rng.integers(8, 50)), int(rng.integers(8, 50))
            image[y : y + h, x : x + w] = shade
        else:
            radius = int(rng.integers(4, 25))
            image[(rows - y) ** 2 + (cols - x) ** 2 <= radius**2] = shade
    noise = rng.normal(0, 4, size=image.shape)
    return np.clip(image + noise, 0, 255).astype(np.uint8)


@pytest.fixture
def image_folder(tmp_path) -> Path:
    rng = np.random.default_rng(5)
    folder = tmp_path / "images"
    (folder / "sub").mkdir(parents=True)
    for i in range(6):
        target = folder / ("sub" if i % 2 else "") / f"{i:03d}.png"
        _core.write_image(str(target), textured_image(rng))
    return folder


def test_cli_vocab_train_and_info(image_folder, tmp_path, capsys):
    out = tmp_path / "vocab" / "orb.slvoc"
    args = ["vocab", "train", str(image_folder), "--out", str(out), "--branching", "5"]
    assert main([*args, "--levels", "3", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert "from 6 images" in printed
    vocabulary = Vocabulary.load(out)
    assert vocabulary.descriptor_type == "binary"
    assert vocabulary.descriptor_cols == 32
    assert 25 < vocabulary.num_words <= 125
    assert vocabulary.branching == 5 and vocabulary.levels == 3

    assert main(["vocab", "info", str(out)]) == 0
    assert f"words        {vocabulary.num_words}" in capsys.readouterr().out

    # --max-images picks an evenly spread subset; same seed, same file.
    again = tmp_path / "again.slvoc"
    assert main([*args, "--levels", "3", "--no-progress", "--out", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()
    few = tmp_path / "few.slvoc"
    assert main([*args, "--levels", "2", "--max-images", "2", "--out", str(few)]) == 0
    assert "from 2 images" in capsys.readouterr().out


def test_cli_vocab_errors_are_one_line(image_folder, tmp_path):
    good = tmp_path / "good.slvoc"
    assert main(["vocab", "train", str(image_folder), "--out", str(good), "--no-progress"]) == 0
    data = bytearray(good.read_bytes())
    data[len(data) // 2] ^= 0x01
    bad = tmp_path / "bad.slvoc"
    bad.write_bytes(bytes(data))
    for path, problem in ((bad, "checksum"), (tmp_path / "missing.slvoc", "cannot open")):
        result = subprocess.run(
            [sys.executable, "-m", "slslam", "vocab", "info", str(path)],
            capture_output=True,
            text=True,
        )
        assert result.returncode != 0
        assert "Traceback" not in result.stderr
        lines = [line for line in result.stderr.splitlines() if line.strip()]
        assert len(lines) == 1, result.stderr
        assert str(path) in lines[0] and problem in lines[0]
    with pytest.raises(VocabularyError, match="checksum"):
        Vocabulary.load(bad)
    assert main(["vocab", "train", str(tmp_path / "nowhere"), "--out", str(good)]) == 2


def test_default_vocabulary_is_shipped_and_loads():
    path = default_vocabulary_path()
    assert path.name == "orb_vocabulary.slvoc"
    assert path.is_relative_to(Path(slslam.__file__).parent)  # package data, installed
    assert path.stat().st_size < 1024 * 1024
    vocabulary = Vocabulary.load(path)
    assert vocabulary.descriptor_type == "binary"
    assert vocabulary.descriptor_cols == 32
    assert vocabulary.num_words > 1000
    # SuperPoint's weights are not redistributable: no vocabulary ships for it.
    with pytest.raises(VocabularyError, match="vocab train --frontend superpoint"):
        default_vocabulary_path("superpoint")
    with pytest.raises(InputError, match="orb, xfeat, superpoint"):
        default_vocabulary_path("binary")


def test_xfeat_vocabulary_is_shipped_float_and_small():
    path = default_vocabulary_path("xfeat")
    assert path.name == "xfeat_vocabulary.slvoc"
    assert path.is_relative_to(Path(slslam.__file__).parent)  # package data, installed
    assert path.stat().st_size <= 1.5e6
    vocabulary = Vocabulary.load(path)
    assert vocabulary.descriptor_type == "float"
    assert vocabulary.descriptor_cols == 64  # XFeat's descriptor width
    assert vocabulary.num_words > 1000


def test_default_vocabulary_tells_places_apart():
    from slslam.features.orb import Orb

    vocabulary = Vocabulary.load(default_vocabulary_path())
    rng = np.random.default_rng(8)
    scene_a, scene_b = textured_image(rng), textured_image(rng)
    orb = Orb()
    # The same scene moved by a few pixels, against another scene.
    a = vocabulary.transform(orb.detect(scene_a).descriptors)
    a_shifted = vocabulary.transform(orb.detect(np.roll(scene_a, (3, 5), axis=(0, 1))).descriptors)
    b = vocabulary.transform(orb.detect(scene_b).descriptors)
    assert Vocabulary.score(a, a_shifted) > 1.5 * Vocabulary.score(a, b)


def test_xfeat_vocabulary_tells_places_apart():
    from slslam.features import XFeat

    vocabulary = Vocabulary.load(default_vocabulary_path("xfeat"))
    rng = np.random.default_rng(8)
    scene_a, scene_b = textured_image(rng), textured_image(rng)
    xfeat = XFeat()
    a = vocabulary.transform(xfeat.detect(scene_a).descriptors)
    a_shifted = vocabulary.transform(
        xfeat.detect(np.roll(scene_a, (3, 5), axis=(0, 1))).descriptors
    )
    b = vocabulary.transform(xfeat.detect(scene_b).descriptors)
    assert Vocabulary.score(a, a_shifted) > 1.5 * Vocabulary.score(a, b)


def test_cli_vocab_train_xfeat_writes_a_float_vocabulary(image_folder, tmp_path, capsys):
    out = tmp_path / "xfeat.slvoc"
    args = ["vocab", "train", str(image_folder), "--out", str(out), "--frontend", "xfeat"]
    assert main([*args, "--branching", "4", "--levels", "3", "--no-progress"]) == 0
    assert "xfeat descriptors from 6 images" in capsys.readouterr().out
    vocabulary = Vocabulary.load(out)
    assert vocabulary.descriptor_type == "float"
    assert vocabulary.descriptor_cols == 64
    assert 16 < vocabulary.num_words <= 64
    assert main([*args, "--frontend", "sift", "--no-progress"]) == 2
    assert "orb, xfeat or superpoint" in capsys.readouterr().err
