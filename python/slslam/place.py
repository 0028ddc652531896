"""Place recognition: a bag-of-words vocabulary and a keyframe database (C++ core, DBoW2-style).

A :class:`Vocabulary` is a hierarchical k-means tree over binary (ORB, Hamming) or float
(XFeat, SuperPoint: L2) descriptors; ``transform`` gives an image's TF-IDF bag-of-words vector and
``score`` compares two of them (1 identical, 0 nothing shared). :class:`KeyframeDatabase` finds the
keyframes whose vectors share most words with a query. The vocabulary files (``.slvoc``) are a
compact checksummed binary format; slslam ships an ORB and an XFeat vocabulary trained on
simulated frames (:func:`default_vocabulary_path`).

    >>> from slslam.place import Vocabulary, default_vocabulary_path
    >>> vocabulary = Vocabulary.load(default_vocabulary_path("orb"))
    >>> bow = vocabulary.transform(orb_descriptors)  # {word: weight}
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from slslam import _core
from slslam.errors import InputError

DescriptorKind = Literal["binary", "float"]
BowVector = dict[int, float]
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".pgm", ".bmp")
DATA_DIR = Path(__file__).resolve().parent / "data"
#: The vocabulary shipped for each point front end (``features.point_frontend``). SuperPoint has
#: none: its weights are not redistributable, so neither is a vocabulary trained on its output.
SHIPPED_VOCABULARIES: dict[str, str] = {
    "orb": "orb_vocabulary.slvoc",
    "xfeat": "xfeat_vocabulary.slvoc",
}
FRONTENDS = ("orb", "xfeat", "superpoint")

KeyframeDatabase = _core.KeyframeDatabase
PlaceCandidate = _core.PlaceCandidate


class VocabularyError(InputError):
    """A vocabulary file is missing, corrupt or of another format version."""


#: Largest IDF weight a word may have. Training gives log(N / n_w) over N images, and
#: log(2^64) = 44.4 bounds that for any image count a machine can hold: a larger weight is a
#: corrupt or forged file (it would let one word outweigh every other in each score).
MAX_IDF_WEIGHT = 64.0
#: The .slvoc layout (cpp/slslam/place/vocabulary_io.cpp): a 32-byte header (magic, version,
#: kind, cols, k, L, node count; uint32 little-endian), nodes of parent int32, word int32,
#: weight float64 and the descriptor, then an 8-byte checksum.
_HEADER_BYTES, _CHECKSUM_BYTES = 32, 8
_MAGIC = b"SLSVOCAB"


def check_vocabulary_records(path: Path) -> None:
    """The word weights of the ``.slvoc`` file at ``path`` are within [0, MAX_IDF_WEIGHT];
    VocabularyError naming the file and the word otherwise. A file whose header or size does
    not fit the layout is left to the C++ loader, which names that defect itself."""
    with path.open("rb") as f:
        header = f.read(_HEADER_BYTES)
        if len(header) < _HEADER_BYTES or header[:8] != _MAGIC:
            return
        _, kind, cols, _, _, nodes = np.frombuffer(header[8:], "<u4").tolist()
        descriptor = {1: ("u1", 1), 2: ("<f4", 4)}.get(kind)
        size = path.stat().st_size
        if descriptor is None or not 0 < cols <= 1 << 16:
            return
        record = np.dtype(
            [("parent", "<i4"), ("word", "<i4"), ("weight", "<f8"), ("d", descriptor[0], cols)]
        )
        if size != _HEADER_BYTES + nodes * record.itemsize + _CHECKSUM_BYTES:
            return
        table = np.fromfile(f, dtype=record, count=nodes)
    words = table["word"] >= 0
    weights = table["weight"][words]
    bad = ~(np.isfinite(weights) & (weights >= 0) & (weights <= MAX_IDF_WEIGHT))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise VocabularyError(
            path,
            f"word {int(table['word'][words][i])} has IDF weight {float(weights[i]):.6g}: "
            f"weights must be finite and in [0, {MAX_IDF_WEIGHT:g}]",
        )


@dataclass(frozen=True)
class VocabularyOptions:
    """Hierarchical k-means settings (the C++ ``VocabularyOptions``)."""

    branching: int = 10  # k of the k-means tree [-]
    levels: int = 4  # depth L of the tree; at most k^L words [-]
    kmeans_iterations: int = 15  # Lloyd iterations per node [-]
    seed: int = 0  # k-means++ seed; same seed and data, same vocabulary

    def to_core(self) -> _core.VocabularyOptions:
        """The C++ options, checked (InputError naming the option): integers in range before
        they reach C++, where an out-of-range value would not fit its type."""
        for name, low, high in (
            ("branching", 2, 2**31 - 1),
            ("levels", 1, 2**31 - 1),
            ("kmeans_iterations", 1, 2**31 - 1),
            ("seed", 0, 2**64 - 1),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
                raise InputError(
                    None,
                    f"vocabulary option {name} must be an integer in [{low}, {high}], got "
                    f"{value!r:.40}",
                )
        core = _core.VocabularyOptions()
        core.branching = self.branching
        core.levels = self.levels
        core.kmeans_iterations = self.kmeans_iterations
        core.seed = self.seed
        core.check()
        return core


def _as_descriptors(array: np.ndarray, what: str) -> np.ndarray:
    array = np.asarray(array)
    if array.ndim != 2:
        raise InputError(None, f"{what} must be a 2-D (N, D) array, got shape {array.shape}")
    if array.dtype not in (np.uint8, np.float32):
        raise InputError(None, f"{what} must be uint8 (binary) or float32, got {array.dtype}")
    return np.ascontiguousarray(array)


def _strip_path(message: str, path: Path) -> str:
    prefix = f"{path}: "
    return message[len(prefix) :] if message.startswith(prefix) else message


class Vocabulary:
    """A trained or loaded bag-of-words vocabulary (immutable; safe to share between threads)."""

    def __init__(self, core: _core.Vocabulary) -> None:
        self._core = core

    @classmethod
    def train(
        cls,
        descriptors_per_image: Sequence[np.ndarray],
        options: VocabularyOptions = VocabularyOptions(),
    ) -> Vocabulary:
        """Train on one (N, D) array per image: all uint8 (ORB) or all float32 (XFeat, ...)."""
        arrays = [
            _as_descriptors(d, f"descriptors_per_image[{i}]")
            for i, d in enumerate(descriptors_per_image)
        ]
        return cls(_core.Vocabulary.train(arrays, options.to_core()))

    @classmethod
    def load(cls, path: str | Path) -> Vocabulary:
        """Read a ``.slvoc`` file; :class:`VocabularyError` names the file and the defect."""
        from slslam.files import special_file_kind

        path = Path(path)
        kind = special_file_kind(path)  # a FIFO or device is refused before it is opened
        if kind is not None and kind != "missing":
            raise VocabularyError(path, f"is {kind}, not a vocabulary file")
        if kind is None:
            check_vocabulary_records(path)
        try:
            return cls(_core.Vocabulary.load(str(path)))
        except ValueError as exc:
            raise VocabularyError(path, _strip_path(str(exc), path)) from None

    def save(self, path: str | Path) -> Path:
        """Write a ``.slvoc`` file (atomically: a ``.partial`` file renamed into place)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            self._core.save(str(path))
        except ValueError as exc:
            raise VocabularyError(path, _strip_path(str(exc), path)) from None
        return path

    @property
    def core(self) -> _core.Vocabulary:
        """The C++ object (for the tracker)."""
        return self._core

    @property
    def num_words(self) -> int:
        return self._core.num_words

    @property
    def num_nodes(self) -> int:
        return self._core.num_nodes

    @property
    def branching(self) -> int:
        return self._core.branching

    @property
    def levels(self) -> int:
        return self._core.levels

    @property
    def descriptor_type(self) -> DescriptorKind:
        """``"binary"`` (uint8, Hamming) or ``"float"`` (float32, L2)."""
        return self._core.descriptor_type

    @property
    def descriptor_cols(self) -> int:
        """Bytes (binary) or floats per descriptor."""
        return self._core.descriptor_cols

    def word_weight(self, word: int) -> float:
        """IDF weight log(N / n) of a word."""
        return self._core.word_weight(word)

    def transform(self, descriptors: np.ndarray) -> BowVector:
        """BoW vector ``{word: weight}`` of one image's descriptors (TF-IDF, weights sum to 1)."""
        return self._core.transform(_as_descriptors(descriptors, "descriptors"))

    def transform_with_features(
        self, descriptors: np.ndarray, levels_up: int = 2
    ) -> tuple[BowVector, dict[int, list[int]]]:
        """BoW vector and direct index ``{node: [rows]}`` at ``levels_up`` above the leaves."""
        return self._core.transform_with_features(
            _as_descriptors(descriptors, "descriptors"), levels_up
        )

    @staticmethod
    def score(a: BowVector, b: BowVector) -> float:
        """L1 similarity 1 - 0.5 |a - b|_1 in [0, 1]."""
        # the stub's Mapping[SupportsInt | SupportsIndex, ...] is invariant in its key: no dict[int]
        return _core.Vocabulary.score(a, b)  # type: ignore[arg-type]

    def __repr__(self) -> str:
        return (
            f"Vocabulary({self.descriptor_type} x {self.descriptor_cols}, {self.num_words} words, "
            f"k={self.branching}, L={self.levels})"
        )


def default_vocabulary_path(frontend: str = "orb") -> Path:
    """The vocabulary shipped with slslam for a point front end: ``"orb"`` (binary, 32 bytes) or
    ``"xfeat"`` (float, 64 values).

    None is shipped for SuperPoint (its weights are not redistributable): train one with
    ``slslam vocab train --frontend superpoint``; :class:`VocabularyError` says so.
    """
    if frontend not in FRONTENDS:
        raise InputError(None, f"frontend must be one of {', '.join(FRONTENDS)}, got {frontend!r}")
    name = SHIPPED_VOCABULARIES.get(frontend)
    if name is None:
        raise VocabularyError(
            None,
            f"slslam ships no {frontend} vocabulary; train one with `slslam vocab train "
            f"--frontend {frontend}`",
        )
    path = DATA_DIR / name
    if not path.is_file():
        raise VocabularyError(path, "the default vocabulary is missing from this installation")
    return path


def find_images(inputs: Iterable[str | Path]) -> list[Path]:
    """Image files among ``inputs``: files as given, folders searched recursively (sorted)."""
    images: list[Path] = []
    for item in map(Path, inputs):
        if item.is_dir():
            found = sorted(p for p in item.rglob("*") if p.suffix.lower() in IMAGE_SUFFIXES)
            if not found:
                raise InputError(item, f"no images ({', '.join(IMAGE_SUFFIXES)}) in this folder")
            images.extend(found)
        elif item.is_file():
            images.append(item)
        else:
            raise InputError(item, "no such file or folder")
    return images


def evenly_spaced(items: Sequence[Path], count: int | None) -> list[Path]:
    """At most ``count`` items spread evenly over the sequence (all when count is None or 0)."""
    if not count or count >= len(items):
        return list(items)
    index = np.linspace(0, len(items) - 1, count).round().astype(int)
    return [items[i] for i in np.unique(index)]


@dataclass(frozen=True)
class TrainingSummary:
    vocabulary: Vocabulary
    images: int
    descriptors: int
    extract_s: float
    train_s: float


def read_image(path: Path) -> np.ndarray:
    """A gray uint8 image; InputError naming the file when it cannot be read."""
    try:
        return _core.read_gray_image(str(path))
    except ValueError as exc:
        raise InputError(path, _strip_path(str(exc), path)) from None


def read_images(paths: Iterable[Path]) -> list[np.ndarray]:
    """Gray uint8 images (``read_image`` each)."""
    return [read_image(p) for p in paths]


def train_from_images(
    images: Sequence[Path],
    detect: Callable[[np.ndarray], np.ndarray],
    options: VocabularyOptions = VocabularyOptions(),
    progress: bool = False,
    between_images: Callable[[], None] | None = None,
) -> TrainingSummary:
    """Extract descriptors with ``detect(gray uint8 image) -> (N, D) array`` and train on them.
    ``between_images`` is called after each image (it may raise to stop, e.g. on a signal)."""
    from tqdm import tqdm

    start = time.perf_counter()
    descriptors = []
    for path in tqdm(images, desc="descriptors", unit="image", disable=not progress):
        image = read_image(path)
        found = detect(image)
        if len(found):
            descriptors.append(found)
        if between_images is not None:
            between_images()
    if not descriptors:
        raise InputError(None, f"no descriptors found in {len(images)} images")
    extracted = time.perf_counter()
    vocabulary = Vocabulary.train(descriptors, options)
    return TrainingSummary(
        vocabulary=vocabulary,
        images=len(descriptors),
        descriptors=sum(len(d) for d in descriptors),
        extract_s=extracted - start,
        train_s=time.perf_counter() - extracted,
    )


__all__ = [
    "SHIPPED_VOCABULARIES",
    "BowVector",
    "KeyframeDatabase",
    "PlaceCandidate",
    "TrainingSummary",
    "Vocabulary",
    "VocabularyError",
    "VocabularyOptions",
    "default_vocabulary_path",
    "evenly_spaced",
    "find_images",
    "train_from_images",
]
