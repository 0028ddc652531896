"""SuperPoint weights: where to get them, checking an ONNX file, converting MagicLeap's .pth.

slslam never ships network weights: MagicLeap's SuperPoint licence (academic / non-commercial
research use, no redistribution) forbids it. Users obtain ``superpoint_v1.pth`` themselves and
convert it once with ``slslam models convert``.
"""

from __future__ import annotations

from pathlib import Path

from slslam.features.superpoint import ENV_MODEL, ModelError, SuperPoint, SuperPointOptions

GUIDE = f"""\
SuperPoint weights are not included in slslam (MagicLeap's licence: academic or non-profit
non-commercial research use only, no redistribution).

1. Read and accept the licence of MagicLeap's "SuperPointPretrainedNetwork" repository and take
   its pretrained file superpoint_v1.pth (about 5 MB).
2. Convert it once (needs PyTorch: pip install torch):
       slslam models convert superpoint_v1.pth superpoint_v1.onnx
3. Tell slslam where it is, either
       export {ENV_MODEL}=/path/to/superpoint_v1.onnx
   or the config key features.superpoint.model_path (it overrides the environment).
4. Check it:
       slslam models check /path/to/superpoint_v1.onnx

Without weights slslam uses the ORB front end and says so.
"""


def check_model(path: str | Path) -> SuperPoint:
    """Load an ONNX file as SuperPoint; ModelError names the file and what does not fit."""
    return SuperPoint(SuperPointOptions(model_path=str(path)))


def _torch_network():
    """SuperPoint's architecture (DeTone et al. 2018, MagicLeap's layer names) in PyTorch."""
    try:
        import torch
        from torch import nn
    except ImportError:
        raise ModelError(None, "converting .pth weights needs PyTorch: pip install torch") from None

    class SuperPointNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            c1, c2, c3, c4, c5 = 64, 64, 128, 128, 256

            def conv(name: str, cin: int, cout: int, k: int = 3) -> None:
                setattr(self, name, nn.Conv2d(cin, cout, k, stride=1, padding=k // 2))

            for name, cin, cout in (
                ("conv1a", 1, c1),
                ("conv1b", c1, c1),
                ("conv2a", c1, c2),
                ("conv2b", c2, c2),
                ("conv3a", c2, c3),
                ("conv3b", c3, c3),
                ("conv4a", c3, c4),
                ("conv4b", c4, c4),
                ("convPa", c4, c5),
                ("convDa", c4, c5),
            ):
                conv(name, cin, cout)
            conv("convPb", c5, 65, 1)
            conv("convDb", c5, 256, 1)
            self.relu = nn.ReLU(inplace=True)
            self.pool = nn.MaxPool2d(2, 2)

        def forward(self, image):
            x = image
            for block in (("conv1a", "conv1b"), ("conv2a", "conv2b"), ("conv3a", "conv3b")):
                for name in block:
                    x = self.relu(getattr(self, name)(x))
                x = self.pool(x)
            x = self.relu(self.conv4b(self.relu(self.conv4a(x))))
            semi = self.convPb(self.relu(self.convPa(x)))
            desc = self.convDb(self.relu(self.convDa(x)))
            desc = desc / torch.linalg.vector_norm(desc, dim=1, keepdim=True).clamp_min(1e-12)
            return semi, desc

    return torch, SuperPointNet()


def convert_pth(pth: str | Path, onnx_path: str | Path) -> Path:
    """Convert MagicLeap's superpoint_v1.pth to ONNX (input 'image' [N,1,H,W], outputs 'semi',
    'desc'; N, H and W dynamic) and check the result."""
    pth, onnx_path = Path(pth), Path(onnx_path)
    if not pth.is_file():
        raise ModelError(pth, "weights file not found")
    torch, net = _torch_network()
    try:
        state = torch.load(pth, map_location="cpu", weights_only=True)
        net.load_state_dict(state, strict=True)
    except Exception as exc:  # wrong file, wrong keys or shapes
        raise ModelError(pth, f"not SuperPoint v1 weights ({exc})") from None
    net.eval()
    onnx_path.parent.mkdir(parents=True, exist_ok=True)
    torch.onnx.export(
        net,
        torch.zeros(1, 1, 480, 752),
        str(onnx_path),
        input_names=["image"],
        output_names=["semi", "desc"],
        opset_version=17,
        dynamo=False,
        dynamic_axes={
            "image": {0: "N", 2: "H", 3: "W"},
            "semi": {0: "N", 2: "Hc", 3: "Wc"},
            "desc": {0: "N", 2: "Hc", 3: "Wc"},
        },
    )
    check_model(onnx_path)
    return onnx_path
