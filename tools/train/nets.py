"""What every trainer of a small CNN shares: torch set up for this CPU, and the ONNX export that
OpenCV 4.6's dnn and the own kernels (libfacetrack/src/nn) load."""
import torch


def setup_torch(threads, seed=None):
    """`threads` CPU threads, the seed when given, and denormals flushed to zero (about 9x faster for small
    nets on this CPU)."""
    torch.set_flush_denormal(True)
    torch.set_num_threads(threads)
    if seed is not None:
        torch.manual_seed(seed)


def export_onnx(net, input_shape, path, output_name):
    """`net` in eval mode as ONNX at opset 13, for an input of `input_shape` (N, C, H, W):
    BatchNorm folded into the convolutions, so only Conv, Relu, Flatten, Gemm (and Softmax) remain."""
    torch.onnx.export(net.eval(), torch.zeros(*input_shape), path, opset_version=13, input_names=["patch"],
                      output_names=[output_name], do_constant_folding=True, training=torch.onnx.TrainingMode.EVAL)


def standardise(x):
    """Patches (N, 1, H, W, floats) -> per patch zero mean, unit population standard deviation:
    what the runtime does before each net (nn::PatchNet)."""
    mean = x.mean(dim=(2, 3), keepdim=True)
    std = x.std(dim=(2, 3), keepdim=True, unbiased=False).clamp_min(1e-3)
    return (x - mean) / std


def _varint(buf, pos):
    """The varint at buf[pos:] and the position after it."""
    value, shift = 0, 0
    while True:
        b = buf[pos]
        pos += 1
        value |= (b & 0x7F) << shift
        shift += 7
        if b < 0x80:
            return value, pos


def _packed_varints(buf):
    values, pos = [], 0
    while pos < len(buf):
        value, pos = _varint(buf, pos)
        values.append(value)
    return values


def _fields(buf):
    """The (field number, wire type, value) of a protobuf message's bytes: varints as ints,
    length-delimited fields as bytes, fixed 32 / 64-bit fields as their raw bytes."""
    pos = 0
    while pos < len(buf):
        key, pos = _varint(buf, pos)
        number, wire = key >> 3, key & 7
        if wire == 0:
            value, pos = _varint(buf, pos)
            yield number, wire, value
            continue
        if wire == 2:
            n, pos = _varint(buf, pos)
        elif wire in (1, 5):
            n = 8 if wire == 1 else 4
        else:
            raise ValueError(f"ONNX: protobuf wire type {wire} not read")
        yield number, wire, bytes(buf[pos:pos + n])
        pos += n


def onnx_chain(onnx):
    """A plain chain that export_onnx wrote (Conv, Relu, Flatten, Gemm; BatchNorm folded), from the ONNX
    file's bytes, back as a torch.nn.Sequential in eval mode: to evaluate a net shipped inside a model
    file whose checkpoint is gone. Only the ONNX protobuf fields such a chain uses are read."""
    import numpy as np
    graph = next(v for n, w, v in _fields(onnx) if n == 7)
    tensors, nodes = {}, []
    for number, _, value in _fields(graph):
        if number == 5:  # initializer: dims 1, data_type 2, float_data 4, name 8, raw_data 9
            dims, name, data = [], "", None
            for n, w, v in _fields(value):
                if n == 1:
                    dims += [v] if w == 0 else list(_packed_varints(v))
                elif n == 8:
                    name = v.decode()
                elif n == 9:
                    data = np.frombuffer(v, "<f4")
                elif n == 4:
                    data = np.frombuffer(v, "<f4") if w == 2 else np.append(data if data is not None else [], np.frombuffer(v, "<f4"))
            tensors[name] = torch.tensor(np.array(data, np.float32).reshape(dims))
        elif number == 1:  # node: input 1, output 2, op_type 4, attribute 5 (name 1, i 3, ints 8)
            inputs, op, attributes = [], "", {}
            for n, w, v in _fields(value):
                if n == 1:
                    inputs.append(v.decode())
                elif n == 4:
                    op = v.decode()
                elif n == 5:
                    fields = list(_fields(v))
                    key = next(x for m, _, x in fields if m == 1).decode()
                    ints = [x for m, w2, x in fields if m == 8 and w2 == 0] + \
                        [i for m, w2, x in fields if m == 8 and w2 == 2 for i in _packed_varints(x)]
                    single = [x for m, _, x in fields if m == 3]
                    attributes[key] = ints if ints else (single[0] if single else None)
            nodes.append((op, inputs, attributes))
    layers = []
    for op, inputs, attributes in nodes:
        if op == "Conv":
            w = tensors[inputs[1]]
            conv = torch.nn.Conv2d(w.shape[1], w.shape[0], tuple(w.shape[2:]), tuple(attributes.get("strides", [1, 1])),
                                   tuple(attributes.get("pads", [0, 0, 0, 0])[:2]), bias=len(inputs) > 2)
            conv.weight.data = w
            if len(inputs) > 2:
                conv.bias.data = tensors[inputs[2]]
            layers.append(conv)
        elif op == "Relu":
            layers.append(torch.nn.ReLU())
        elif op == "Flatten":
            layers.append(torch.nn.Flatten())
        elif op == "Gemm":
            w = tensors[inputs[1]]
            if not attributes.get("transB"):
                w = w.t()
            linear = torch.nn.Linear(w.shape[1], w.shape[0])
            linear.weight.data, linear.bias.data = w.contiguous(), tensors[inputs[2]]
            layers.append(linear)
        else:
            raise ValueError(f"ONNX: a {op} node is not part of a plain chain")
    return torch.nn.Sequential(*layers).eval()

