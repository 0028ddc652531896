"""XFeat's graph rewrites (slslam.features.xfeat_graph): each gives the same outputs.

The export applies them to PyTorch's graph and compares the outputs itself (test_xfeat.py runs
the export where torch is installed); here they run on small graphs built with onnx's helper API,
so CI checks them without torch.
"""

from __future__ import annotations

import numpy as np
import pytest

onnx = pytest.importorskip("onnx", reason="the graphs are built with onnx's helper API")
ort = pytest.importorskip("onnxruntime")

from onnx import TensorProto, helper, numpy_helper  # noqa: E402

from slslam.features import xfeat_graph  # noqa: E402
from slslam.features.superpoint import ModelError  # noqa: E402
from slslam.features.xfeat import SHIPPED_MODEL  # noqa: E402


def _run(model, feeds):
    session = ort.InferenceSession(model.SerializeToString(), providers=["CPUExecutionProvider"])
    return session.run(None, feeds)


def _model(nodes, inputs, outputs, initializers):
    graph = helper.make_graph(nodes, "g", inputs, outputs, initializers)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.checker.check_model(model)
    return model


@pytest.mark.parametrize(
    "stride, f_in, f_out", [(1, 2, 2), (2, 2, 2), (2, 2, 1), (1, 4, 4), (2, 4, 2), (1, 1, 2)]
)
def test_phase_kernel_is_the_plain_convolution(stride, f_in, f_out):
    """Plain input -> Conv against SpaceToDepth(f_in) -> phase Conv -> DepthToSpace(f_out), on
    random weights and an image whose sides the phases divide."""
    rng = np.random.default_rng(stride * 100 + f_in * 10 + f_out)
    c_in, c_out, h, w = 3, 5, 32, 48
    weight = rng.normal(size=(c_out, c_in, 3, 3)).astype(np.float32)
    bias = rng.normal(size=c_out).astype(np.float32)
    kernel, phase_bias, block_stride, k, lead = xfeat_graph.phase_kernel(
        weight, bias, stride, f_in, f_out
    )
    assert kernel.shape[:2] == (c_out * f_out**2, c_in * f_in**2)
    x = rng.normal(size=(1, c_in, h, w)).astype(np.float32)
    plain = _model(
        [helper.make_node("Conv", ["x", "w", "b"], ["y"], pads=[1] * 4, strides=[stride] * 2)],
        [helper.make_tensor_value_info("x", TensorProto.FLOAT, list(x.shape))],
        [helper.make_tensor_value_info("y", TensorProto.FLOAT, ["n", "c", "h", "w"])],
        [numpy_helper.from_array(weight, "w"), numpy_helper.from_array(bias, "b")],
    )
    nodes, source = [], "x"
    if f_in > 1:
        nodes.append(helper.make_node("SpaceToDepth", ["x"], ["xp"], blocksize=f_in))
        source = "xp"
    pads = [lead, lead, k - 1 - lead, k - 1 - lead]
    nodes.append(
        helper.make_node("Conv", [source, "w", "b"], ["yp"], pads=pads, strides=[block_stride] * 2)
    )
    if f_out > 1:
        nodes.append(helper.make_node("DepthToSpace", ["yp"], ["y"], blocksize=f_out, mode="DCR"))
    else:
        nodes.append(helper.make_node("Identity", ["yp"], ["y"]))
    phased = _model(
        nodes,
        [helper.make_tensor_value_info("x", TensorProto.FLOAT, list(x.shape))],
        [helper.make_tensor_value_info("y", TensorProto.FLOAT, ["n", "c", "h", "w"])],
        [numpy_helper.from_array(kernel, "w"), numpy_helper.from_array(phase_bias, "b")],
    )
    (expected,), (got,) = _run(plain, {"x": x}), _run(phased, {"x": x})
    assert got.shape == expected.shape == (1, c_out, h // stride, w // stride)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-4)


def test_phase_kernel_refuses_a_fractional_stride():
    weight = np.zeros((2, 2, 3, 3), np.float32)
    with pytest.raises(xfeat_graph.GraphRewriteError, match="whole stride"):
        xfeat_graph.phase_kernel(weight, np.zeros(2, np.float32), 1, 4, 2)


def _xfeat_like(h: int = 64, w: int = 96):
    """The start of XFeat's exported graph with its node names: the channel mean, the instance
    norm, block 1 (four 3 x 3 convolutions and ReLUs) with the skip branch added to it, and the
    keypoint head's unshuffle as PyTorch writes it (reshapes around a six-dimensional Transpose,
    constant shapes here)."""
    rng = np.random.default_rng(7)
    channels = [(1, 4, 1), (4, 8, 2), (8, 8, 1), (8, 24, 2)]
    nodes = [
        helper.make_node("ReduceMean", ["image"], ["mean"], name="/net/ReduceMean", axes=[1]),
        helper.make_node("InstanceNormalization", ["mean", "scale", "shift"], ["norm"]),
    ]
    inits = [
        numpy_helper.from_array(np.ones(1, np.float32), "scale"),
        numpy_helper.from_array(np.zeros(1, np.float32), "shift"),
    ]
    source = "norm"
    for (name, _, _), (c_in, c_out, stride) in zip(
        xfeat_graph.BLOCK1_PHASES, channels, strict=True
    ):
        weight = rng.normal(scale=0.5, size=(c_out, c_in, 3, 3)).astype(np.float32)
        inits += [
            numpy_helper.from_array(weight, name + ".w"),
            numpy_helper.from_array(rng.normal(size=c_out).astype(np.float32), name + ".b"),
        ]
        nodes += [
            helper.make_node(
                "Conv",
                [source, name + ".w", name + ".b"],
                [name + "_out"],
                name=name,
                kernel_shape=[3, 3],
                pads=[1] * 4,
                strides=[stride] * 2,
            ),
            helper.make_node("Relu", [name + "_out"], [name + "_relu"]),
        ]
        source = name + "_relu"
    # the skip branch beside block 1: a 4 x 4 average pool and a 1 x 1 convolution, added
    inits += [
        numpy_helper.from_array(rng.normal(size=(24, 1, 1, 1)).astype(np.float32), "skip.w"),
        numpy_helper.from_array(rng.normal(size=24).astype(np.float32), "skip.b"),
    ]
    nodes += [
        helper.make_node(
            "AveragePool",
            ["norm"],
            ["pooled"],
            name=xfeat_graph.SKIP_POOL,
            kernel_shape=[4, 4],
            strides=[4, 4],
        ),
        helper.make_node(
            "Conv", ["pooled", "skip.w", "skip.b"], ["skip"], name=xfeat_graph.SKIP_CONV
        ),
        helper.make_node("Add", [source, "skip"], ["block1"]),
    ]
    shapes = {"s1": [1, 1, h // 8, 8, w // 8, 8], "s2": [1, 64, h // 8, w // 8]}
    inits += [numpy_helper.from_array(np.array(v, np.int64), k) for k, v in shapes.items()]
    nodes += [
        helper.make_node("Reshape", ["norm", "s1"], ["r1"], name="/net/Reshape"),
        helper.make_node(
            "Transpose", ["r1"], ["t"], name="/net/Transpose", perm=[0, 1, 3, 5, 2, 4]
        ),
        helper.make_node("Reshape", ["t", "s2"], ["unshuffled"], name="/net/Reshape_2"),
    ]
    return _model(
        nodes,
        [helper.make_tensor_value_info("image", TensorProto.FLOAT, [1, 1, h, w])],
        [
            helper.make_tensor_value_info("block1", TensorProto.FLOAT, ["n", "c", "h", "w"]),
            helper.make_tensor_value_info("unshuffled", TensorProto.FLOAT, ["n", "c", "h", "w"]),
        ],
        inits,
    )


def test_optimise_keeps_the_outputs_of_an_xfeat_like_graph():
    model = _xfeat_like()
    image = np.random.default_rng(1).integers(0, 256, (1, 1, 64, 96)).astype(np.float32)
    before = _run(model, {"image": image})
    xfeat_graph.optimise(model)
    ops = [n.op_type for n in model.graph.node]
    assert "ReduceMean" not in ops and "Transpose" not in ops and "Reshape" not in ops
    assert "AveragePool" not in ops
    assert ops.count("SpaceToDepth") == 2  # the unshuffle and block 1's phases
    after = _run(model, {"image": image})
    assert after[0].shape == before[0].shape == (1, 24, 16, 24)
    np.testing.assert_allclose(after[0], before[0], rtol=0, atol=1e-4 * np.abs(before[0]).max())
    np.testing.assert_array_equal(after[1], before[1])  # a permutation: exact


def test_optimise_refuses_another_graph_and_the_export_names_the_file(tmp_path):
    model = _xfeat_like()
    model.graph.node.remove(next(n for n in model.graph.node if n.op_type == "ReduceMean"))
    with pytest.raises(xfeat_graph.GraphRewriteError, match="channel mean"):
        xfeat_graph.optimise(model)
    # a ReLU read by another node, or a graph output: the phase layout would leak
    for read_by in ("node", "output"):
        model = _xfeat_like()
        relu = model.graph.node[3]  # block1.0's ReLU
        assert relu.op_type == "Relu"
        if read_by == "node":
            model.graph.node.append(helper.make_node("Identity", [relu.output[0]], ["leak"]))
        else:
            model.graph.output.append(
                helper.make_tensor_value_info(
                    relu.output[0], TensorProto.FLOAT, ["n", "c", "h", "w"]
                )
            )
        with pytest.raises(xfeat_graph.GraphRewriteError, match="through one ReLU alone"):
            xfeat_graph.phase_convolutions(model)
    # an unshuffle of another block size is left alone
    model = _xfeat_like()
    shape = next(t for t in model.graph.initializer if t.name == "s1")
    shape.CopyFrom(numpy_helper.from_array(np.array([1, 1, 16, 4, 24, 4], np.int64), "s1"))
    target = next(t for t in model.graph.initializer if t.name == "s2")
    target.CopyFrom(numpy_helper.from_array(np.array([1, 16, 16, 24], np.int64), "s2"))
    assert xfeat_graph.unshuffle_as_space_to_depth(model) == 0

    from slslam.features.xfeat_export import write_optimised

    traced = tmp_path / "traced.onnx"
    plain = _xfeat_like()
    plain.graph.node.remove(next(n for n in plain.graph.node if n.op_type == "Transpose"))
    onnx.save(plain, str(traced))
    with pytest.raises(ModelError, match=r"traced\.onnx"):
        write_optimised(traced, tmp_path / "out.onnx")
    assert not (tmp_path / "out.onnx").exists()


def test_the_shipped_file_is_the_rewritten_graph():
    if not SHIPPED_MODEL.is_file():
        pytest.skip(f"{SHIPPED_MODEL} is not installed")
    ops = [n.op_type for n in onnx.load(str(SHIPPED_MODEL)).graph.node]
    assert "ReduceMean" not in ops and "Transpose" not in ops
    assert ops.count("SpaceToDepth") == 2


def test_shipped_int8_file_sees_the_whole_gray_range():
    """The image enters the 8-bit network unquantised (the instance normalisation stays in float,
    xfeat_quantize.FLOAT_NODES): gray levels above the calibration frames' brightest (176) are
    not clipped, so an image and its copy clipped at 176 give different keypoint logits."""
    from slslam.features.xfeat import SHIPPED_INT8_MODEL

    if not SHIPPED_INT8_MODEL.is_file():
        pytest.skip(f"{SHIPPED_INT8_MODEL} is not installed")
    model = onnx.load(str(SHIPPED_INT8_MODEL))
    readers = [n.op_type for n in model.graph.node if "image" in n.input]
    assert readers == ["InstanceNormalization"]
    image = np.random.default_rng(3).integers(0, 256, (1, 1, 96, 128)).astype(np.float32)
    logits = [_run(model, {"image": x})[1] for x in (image, np.minimum(image, 176.0))]
    assert np.abs(logits[0] - logits[1]).max() > 1.0


def test_quantising_another_graph_names_the_file(tmp_path):
    from slslam.features.xfeat_quantize import quantize_xfeat

    source = tmp_path / "other.onnx"
    onnx.save(_xfeat_like(), str(source))
    with pytest.raises(ModelError, match=r"other\.onnx.*keep in float"):
        quantize_xfeat(tmp_path / "x8.onnx", images=[np.zeros((64, 96), np.uint8)], source=source)


def test_models_commands_name_a_missing_onnx_package(monkeypatch, tmp_path, capsys):
    """Without the onnx package the quantise command ends with one error line, no traceback."""
    import sys

    from slslam.cli import main

    for name in [m for m in sys.modules if m == "onnx" or m.startswith(("onnx.", "onnxruntime.q"))]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "onnx", None)  # import onnx raises ImportError
    assert main(["models", "quantize", "xfeat", "--out", str(tmp_path / "x8.onnx")]) == 2
    assert "pip install onnx" in capsys.readouterr().err
