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
