#pragma once
// The project's small CNNs (the landmark and brow refiners, the cascade's nets,
// an iris net) run with own kernels: a plain chain of convolutions, ReLUs,
// fully connected layers and a softmax over channels, read off the net that
// OpenCV's dnn loaded from ONNX. On the refiners they take about 0.7x of dnn's
// time and allocate nothing per call (docs/cnn.md, "The CNN file and the runtime").
//
// A convolution with stride s, dilation d and padding (p_y, p_x) computes
//   out(y, x, o) = b_o + sum_{dy, dx, i} W(o, i, dy, dx) in(s y + d dy - p_y, s x + d dx - p_x, i)
// (zero outside the input), in register blocks of 4-8 output pixels x 8-16
// output channels. Activations are kept height x width x channels, the
// channels padded to a multiple of 8; each layer writes into the interior of
// the next one's zero-bordered input. The fully connected layers run after
// the convolutions of every item, reading each weight row once for two items.
// Where the CPU has AVX2 and FMA the same loops are compiled for them.

#include <opencv2/dnn.hpp>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace facetrack::nn {

class ConvChain {
public:
    /// The chain that `net` computes for an input of `shape` (N x C x H x W),
    /// or nullopt with the reason in `whyNot` when the net is not such a chain
    /// (another layer type, a grouped convolution, a branch). Reads the layers'
    /// weights; does not run the net.
    static std::optional<ConvChain> fromNet(const cv::dnn::Net& net, std::array<int, 4> shape, std::string& whyNot);

    /// The values the chain gives for one input of the batch.
    int outputsPerItem() const { return layers_.outputs_per_item; }

    /// out (N x outputsPerItem(), in the net's NCHW order) for `in` (N x C x H
    /// x W). Not thread-safe (the chain keeps its activations): one per thread.
    void forward(const float* in, float* out);
    /// The same with the kernels built for any x86-64, which forward() runs
    /// where the CPU lacks AVX2 or FMA (tests compare the two).
    void forwardPortable(const float* in, float* out);

    /// A convolution of the chain, and the ReLU after it if any.
    struct Conv {
        int in_channels = 0, out_channels = 0;  ///< as the net has them
        int in_padded = 0, out_padded = 0;      ///< rounded up to 8
        int kernel_h = 0, kernel_w = 0, stride_y = 1, stride_x = 1, dilation_y = 1, dilation_x = 1;
        int pad_top = 0, pad_left = 0, pad_bottom = 0, pad_right = 0;
        int in_h = 0, in_w = 0, out_h = 0, out_w = 0;
        std::vector<float> weights;  ///< [dy][dx][i < in_padded][o < out_padded]
        std::vector<float> bias;     ///< out_padded
        bool relu = false;
    };
    /// A fully connected layer, and the ReLU after it if any.
    struct Dense {
        int inputs = 0, inputs_padded = 0, outputs = 0;
        std::vector<float> weights;  ///< [o][i < inputs_padded], the inputs in the chain's order
        std::vector<float> bias;     ///< outputs
        bool relu = false;
    };
    /// The layers and their buffers.
    struct Layers {
        int batch = 1, in_channels = 1, in_h = 0, in_w = 0;
        std::vector<Conv> convs;    ///< first, in order
        std::vector<Dense> denses;  ///< then these, in order
        bool softmax = false;       ///< over the last convolution's channels (a net with
                                    ///< no dense layer)
        int outputs_per_item = 0;
        /// convs[k]'s input inside its zero border; the last, the last
        /// convolution's output for every item of the batch.
        std::vector<std::vector<float>> activations;
        /// The dense layers' outputs between them, dense_floats per item.
        std::vector<float> dense_in, dense_out;
        int dense_floats = 0;
    };

private:
    explicit ConvChain(Layers layers);

    Layers layers_;
    bool avx2_ = false;
};

}  // namespace facetrack::nn
