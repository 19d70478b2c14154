#include "nn/conv_chain.hpp"

#include <opencv2/dnn/all_layers.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace facetrack::nn {

namespace {

using Conv = ConvChain::Conv;
using Dense = ConvChain::Dense;
using Layers = ConvChain::Layers;

int roundUp8(int n) { return (n + 7) / 8 * 8; }

/// Eight floats; GCC and Clang compile them to one AVX register where the
/// function is built for AVX2, to two SSE registers elsewhere.
using Float8 = float __attribute__((vector_size(32)));

/// P output pixels x 8 V output channels (o0 .. o0 + 8 V - 1) of a
/// convolution: the accumulators stay in registers while every tap and input
/// channel goes by. `from[p]`: pixel p's first tap in `in`; `to[p]`: its
/// output in `out`.
template <int P, int V>
[[gnu::always_inline]] inline void convBlock(const Conv& c, const float* in, int inRowFloats, const int* from, const int* to, int o0,
                                             float* out) {
    Float8 acc[P][V];
#pragma GCC unroll 16
    for (int v = 0; v < V; ++v) {
        Float8 b;
        std::memcpy(&b, c.bias.data() + o0 + 8 * v, sizeof b);
#pragma GCC unroll 16
        for (int p = 0; p < P; ++p) acc[p][v] = b;
    }
    for (int dy = 0; dy < c.kernel_h; ++dy) {
        for (int dx = 0; dx < c.kernel_w; ++dx) {
            const float* tap = in + dy * c.dilation_y * inRowFloats + dx * c.dilation_x * c.in_padded;
            const float* w = c.weights.data() + static_cast<std::size_t>((dy * c.kernel_w + dx) * c.in_padded) * c.out_padded + o0;
            for (int i = 0; i < c.in_channels; ++i, w += c.out_padded) {
                Float8 wv[V];
#pragma GCC unroll 16
                for (int v = 0; v < V; ++v) std::memcpy(&wv[v], w + 8 * v, sizeof wv[v]);
#pragma GCC unroll 16
                for (int p = 0; p < P; ++p) {
                    const float a = tap[from[p] + i];
#pragma GCC unroll 16
                    for (int v = 0; v < V; ++v) acc[p][v] += wv[v] * a;
                }
            }
        }
    }
#pragma GCC unroll 16
    for (int p = 0; p < P; ++p) {
        float* o = out + to[p] + o0;
#pragma GCC unroll 16
        for (int v = 0; v < V; ++v) std::memcpy(o + 8 * v, &acc[p][v], sizeof acc[p][v]);
        if (c.relu) {
#pragma GCC unroll 16
            for (int k = 0; k < 8 * V; ++k) o[k] = std::max(o[k], 0.0f);
        }
    }
}

/// The next P output pixels, row by row from (y, x), which it advances: where
/// each reads its first tap and writes its channels.
template <int P>
[[gnu::always_inline]] inline void pixelOffsets(const Conv& c, int inRowFloats, int outRowFloats, int& y, int& x, int* from, int* to) {
    for (int p = 0; p < P; ++p) {
        from[p] = y * c.stride_y * inRowFloats + x * c.stride_x * c.in_padded;
        to[p] = y * outRowFloats + x * c.out_padded;
        if (++x == c.out_w) {
            x = 0;
            ++y;
        }
    }
}

/// The output channels o0 .. o0 + 8 V - 1 at every output pixel, P at a time.
template <int P, int V>
[[gnu::always_inline]] inline void convChannels(const Conv& c, const float* in, int inRowFloats, float* out, int outRowFloats, int o0) {
    const int pixels = c.out_h * c.out_w;
    int from[P], to[P];
    int q = 0, y = 0, x = 0;
    for (; q + P <= pixels; q += P) {
        pixelOffsets<P>(c, inRowFloats, outRowFloats, y, x, from, to);
        convBlock<P, V>(c, in, inRowFloats, from, to, o0, out);
    }
    for (; q < pixels; ++q) {
        pixelOffsets<1>(c, inRowFloats, outRowFloats, y, x, from, to);
        convBlock<1, V>(c, in, inRowFloats, from, to, o0, out);
    }
}

/// One convolution: `in` is its input inside its zero border, `out` the next
/// input's first interior pixel, `outRowFloats` that buffer's row length. The
/// blocks are as large as the registers hold (P V <= 12 accumulators), their
/// shape chosen so that few pixels are left for single-pixel blocks.
[[gnu::always_inline]] inline void runConv(const Conv& c, const float* in, float* out, int outRowFloats) {
    const int inRowFloats = (c.in_w + c.pad_left + c.pad_right) * c.in_padded;
    const int pixels = c.out_h * c.out_w;
    int o0 = 0;
    for (; o0 + 16 <= c.out_padded; o0 += 16) {
        if (pixels % 4 < pixels % 6) {
            convChannels<4, 2>(c, in, inRowFloats, out, outRowFloats, o0);
        } else {
            convChannels<6, 2>(c, in, inRowFloats, out, outRowFloats, o0);
        }
    }
    if (o0 < c.out_padded) convChannels<8, 1>(c, in, inRowFloats, out, outRowFloats, o0);
}

/// out_{n,o} = b_o + sum_i W_oi in_{n,i} over the padded inputs (whose padding is 0), for N items of
/// the batch `inStride` and `outStride` floats apart: each row of W is read once for all N. The
/// hidden layers' weights are most of a net's bytes (a 1152 x 192 layer: 0.9 MB), so a batch of two
/// (a mirror-averaged stage, both brows) reads them from memory once, not twice.
template <int N>
[[gnu::always_inline]] inline void denseItems(const Dense& d, const float* in, int inStride, float* out, int outStride) {
    for (int o = 0; o < d.outputs; ++o) {
        const float* w = d.weights.data() + static_cast<std::size_t>(o) * d.inputs_padded;
        Float8 s[N][4] = {};
        int i = 0;
        for (; i + 32 <= d.inputs_padded; i += 32) {
            for (int k = 0; k < 4; ++k) {
                Float8 a;
                std::memcpy(&a, w + i + 8 * k, sizeof a);
#pragma GCC unroll 4
                for (int n = 0; n < N; ++n) {
                    Float8 b;
                    std::memcpy(&b, in + n * inStride + i + 8 * k, sizeof b);
                    s[n][k] += a * b;
                }
            }
        }
        for (; i < d.inputs_padded; i += 8) {
            Float8 a;
            std::memcpy(&a, w + i, sizeof a);
#pragma GCC unroll 4
            for (int n = 0; n < N; ++n) {
                Float8 b;
                std::memcpy(&b, in + n * inStride + i, sizeof b);
                s[n][0] += a * b;
            }
        }
#pragma GCC unroll 4
        for (int n = 0; n < N; ++n) {
            const Float8 t = (s[n][0] + s[n][1]) + (s[n][2] + s[n][3]);
            float sum = d.bias[static_cast<std::size_t>(o)];
            for (int k = 0; k < 8; ++k) sum += t[k];
            out[n * outStride + o] = d.relu ? std::max(sum, 0.0f) : sum;
        }
    }
}

/// One dense layer for every item of the batch, two at a time. The outputs' padding up to a
/// multiple of 8 is zeroed: the next layer reads it.
[[gnu::always_inline]] inline void runDense(const Dense& d, int batch, const float* in, int inStride, float* out, int outStride) {
    int n = 0;
    for (; n + 2 <= batch; n += 2) denseItems<2>(d, in + n * inStride, inStride, out + n * outStride, outStride);
    if (n < batch) denseItems<1>(d, in + n * inStride, inStride, out + n * outStride, outStride);
    for (n = 0; n < batch && outStride > d.outputs; ++n)
        std::fill(out + n * outStride + d.outputs, out + n * outStride + std::min(roundUp8(d.outputs), outStride), 0.0f);
}

/// The whole chain: the convolutions item by item of the batch, then the dense layers for all items.
[[gnu::always_inline]] inline void runChain(Layers& L, const float* in, float* out) {
    const Conv& first = L.convs.front();
    const Conv& last = L.convs.back();
    const int inPixels = L.in_h * L.in_w;
    const int lastFloats = last.out_h * last.out_w * last.out_padded;  // one item's maps after the last convolution
    for (int item = 0; item < L.batch; ++item) {
        // The item's C x H x W planes into the first input's interior, height x width x channels.
        const float* planes = in + static_cast<std::size_t>(item) * L.in_channels * inPixels;
        float* a0 = L.activations[0].data();
        const int rowFloats0 = (first.in_w + first.pad_left + first.pad_right) * first.in_padded;
        for (int y = 0; y < L.in_h; ++y) {
            float* row = a0 + (y + first.pad_top) * rowFloats0 + first.pad_left * first.in_padded;
            for (int x = 0; x < L.in_w; ++x)
                for (int ch = 0; ch < L.in_channels; ++ch) row[x * first.in_padded + ch] = planes[ch * inPixels + y * L.in_w + x];
        }
        float* maps = L.activations.back().data() + static_cast<std::size_t>(item) * lastFloats;
        for (std::size_t k = 0; k < L.convs.size(); ++k) {
            const Conv& c = L.convs[k];
            float* next = maps;
            int rowFloats = c.out_w * c.out_padded;
            if (k + 1 < L.convs.size()) {
                const Conv& n = L.convs[k + 1];
                rowFloats = (n.in_w + n.pad_left + n.pad_right) * n.in_padded;
                next = L.activations[k + 1].data() + n.pad_top * rowFloats + n.pad_left * n.in_padded;
            }
            runConv(c, L.activations[k].data(), next, rowFloats);
        }
        if (!L.denses.empty()) continue;
        // Height x width x padded channels -> the net's C x H x W, with the softmax over C first.
        float* result = out + static_cast<std::size_t>(item) * L.outputs_per_item;
        const int pixels = last.out_h * last.out_w;
        for (int p = 0; p < pixels; ++p) {
            const float* v = maps + p * last.out_padded;
            if (!L.softmax) {
                for (int ch = 0; ch < last.out_channels; ++ch) result[ch * pixels + p] = v[ch];
                continue;
            }
            const float top = *std::max_element(v, v + last.out_channels);
            float sum = 0.0f;
            for (int ch = 0; ch < last.out_channels; ++ch) sum += (result[ch * pixels + p] = std::exp(v[ch] - top));
            for (int ch = 0; ch < last.out_channels; ++ch) result[ch * pixels + p] /= sum;
        }
    }
    const float* x = L.activations.back().data();
    int xStride = lastFloats;
    for (std::size_t k = 0; k < L.denses.size(); ++k) {
        const bool isLast = k + 1 == L.denses.size();
        float* y = isLast ? out : (k % 2 == 0 ? L.dense_out.data() : L.dense_in.data());
        const int yStride = isLast ? L.outputs_per_item : L.dense_floats;
        runDense(L.denses[k], L.batch, x, xStride, y, yStride);
        x = y;
        xStride = yStride;
    }
}

void runChainGeneric(Layers& L, const float* in, float* out) { runChain(L, in, out); }

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define FACETRACK_CONV_CHAIN_AVX2 1
__attribute__((target("avx2,fma"))) void runChainAvx2(Layers& L, const float* in, float* out) { runChain(L, in, out); }
#endif

/// The blob's floats; its element count must be `count`.
bool readFloats(const cv::Mat& blob, std::size_t count, std::vector<float>& out) {
    if (blob.type() != CV_32F || blob.total() != count || !blob.isContinuous()) return false;
    out.assign(blob.ptr<float>(), blob.ptr<float>() + count);
    return true;
}

}  // namespace

std::optional<ConvChain> ConvChain::fromNet(const cv::dnn::Net& net, std::array<int, 4> shape, std::string& whyNot) {
    Layers L;
    L.batch = shape[0];
    L.in_channels = shape[1];
    L.in_h = shape[2];
    L.in_w = shape[3];
    // The tensor after the layers so far: channels x height x width, or `flat` values once flattened.
    int channels = L.in_channels, height = L.in_h, width = L.in_w;
    bool flat = false, lastIsConv = false;
    std::string previous;
    const auto fail = [&](const std::string& why) {
        whyNot = why;
        return std::nullopt;
    };
    for (const std::string& name : net.getLayerNames()) {
        const int id = net.getLayerId(name);
        const cv::Ptr<cv::dnn::Layer> layer = net.getLayer(id);
        const std::vector<cv::Ptr<cv::dnn::Layer>> inputs = net.getLayerInputs(id);
        if (inputs.size() != 1 || (!previous.empty() && inputs[0]->name != previous))
            return fail("layer " + name + " does not take the previous layer's output alone");
        previous = name;
        const std::string& type = layer->type;
        if (type == "Convolution") {
            const auto conv = layer.dynamicCast<cv::dnn::BaseConvolutionLayer>();
            if (!conv || flat || conv->kernel_size.size() != 2 || conv->strides.size() != 2 || conv->dilations.size() != 2 ||
                conv->pads_begin.size() != 2 || conv->pads_end.size() != 2 || !conv->padMode.empty() || layer->blobs.empty())
                return fail("convolution " + name + " is not a plain 2D convolution");
            const auto within = [](const std::vector<std::size_t>& v, std::size_t low, std::size_t high) {
                return v[0] >= low && v[0] <= high && v[1] >= low && v[1] <= high;
            };
            if (!within(conv->kernel_size, 1, 64) || !within(conv->strides, 1, 64) || !within(conv->dilations, 1, 64) ||
                !within(conv->pads_begin, 0, 1024) || !within(conv->pads_end, 0, 1024))
                return fail("convolution " + name + " has a kernel, stride, dilation or padding the chain does not run");
            const cv::Mat& w = layer->blobs[0];
            if (w.dims != 4 || w.size[1] != channels) return fail("convolution " + name + " is grouped or does not match its input");
            Conv c;
            c.in_channels = channels;
            c.in_padded = L.convs.empty() ? channels : L.convs.back().out_padded;
            c.out_channels = w.size[0];
            c.out_padded = roundUp8(c.out_channels);
            c.kernel_h = static_cast<int>(conv->kernel_size[0]);
            c.kernel_w = static_cast<int>(conv->kernel_size[1]);
            c.stride_y = static_cast<int>(conv->strides[0]);
            c.stride_x = static_cast<int>(conv->strides[1]);
            c.dilation_y = static_cast<int>(conv->dilations[0]);
            c.dilation_x = static_cast<int>(conv->dilations[1]);
            c.pad_top = static_cast<int>(conv->pads_begin[0]);
            c.pad_left = static_cast<int>(conv->pads_begin[1]);
            c.pad_bottom = static_cast<int>(conv->pads_end[0]);
            c.pad_right = static_cast<int>(conv->pads_end[1]);
            c.in_h = height;
            c.in_w = width;
            const int spanY = height + c.pad_top + c.pad_bottom - c.dilation_y * (c.kernel_h - 1) - 1;  // how far the kernel can move
            const int spanX = width + c.pad_left + c.pad_right - c.dilation_x * (c.kernel_w - 1) - 1;
            c.out_h = spanY / c.stride_y + 1;
            c.out_w = spanX / c.stride_x + 1;
            if (w.size[2] != c.kernel_h || w.size[3] != c.kernel_w || spanY < 0 || spanX < 0)
                return fail("convolution " + name + " does not fit its input");
            std::vector<float> raw;
            if (!readFloats(w, w.total(), raw)) return fail("convolution " + name + "'s weights are not 32-bit floats");
            c.weights.assign(static_cast<std::size_t>(c.kernel_h * c.kernel_w * c.in_padded * c.out_padded), 0.0f);
            for (int o = 0; o < c.out_channels; ++o)
                for (int i = 0; i < c.in_channels; ++i)
                    for (int dy = 0; dy < c.kernel_h; ++dy)
                        for (int dx = 0; dx < c.kernel_w; ++dx)
                            c.weights[static_cast<std::size_t>(((dy * c.kernel_w + dx) * c.in_padded + i) * c.out_padded + o)] =
                                raw[static_cast<std::size_t>(((o * c.in_channels + i) * c.kernel_h + dy) * c.kernel_w + dx)];
            c.bias.assign(static_cast<std::size_t>(c.out_padded), 0.0f);
            if (layer->blobs.size() > 1) {
                if (!readFloats(layer->blobs[1], static_cast<std::size_t>(c.out_channels), raw))
                    return fail("convolution " + name + "'s bias does not match its channels");
                std::copy(raw.begin(), raw.end(), c.bias.begin());
            }
            channels = c.out_channels;
            height = c.out_h;
            width = c.out_w;
            L.convs.push_back(std::move(c));
            lastIsConv = true;
        } else if (type == "ReLU") {
            const auto relu = layer.dynamicCast<cv::dnn::ReLULayer>();
            if (!relu || relu->negativeSlope != 0.0f || (!lastIsConv && L.denses.empty()))
                return fail("ReLU " + name + " does not follow a convolution or a dense layer");
            bool& follows = lastIsConv ? L.convs.back().relu : L.denses.back().relu;
            if (follows) return fail("ReLU " + name + " follows another");
            follows = true;
        } else if (type == "Flatten" || type == "Reshape") {
            if (L.convs.empty()) return fail("the net does not start with a convolution");
            flat = true;
        } else if (type == "InnerProduct") {
            const auto dense = layer.dynamicCast<cv::dnn::InnerProductLayer>();
            if (!dense || !flat || dense->axis != 1 || layer->blobs.empty()) return fail("dense layer " + name + " is not a plain one");
            const cv::Mat& w = layer->blobs[0];
            Dense d;
            d.inputs = lastIsConv ? channels * height * width : L.denses.back().outputs;
            if (w.dims != 2 || w.size[1] != d.inputs) return fail("dense layer " + name + " does not match its input");
            d.outputs = w.size[0];
            std::vector<float> raw;
            if (!readFloats(w, w.total(), raw)) return fail("dense layer " + name + "'s weights are not 32-bit floats");
            if (lastIsConv) {
                // The net flattens C x H x W; the chain keeps height x width x padded channels.
                const Conv& c = L.convs.back();
                d.inputs_padded = height * width * c.out_padded;
                d.weights.assign(static_cast<std::size_t>(d.outputs) * d.inputs_padded, 0.0f);
                for (int o = 0; o < d.outputs; ++o)
                    for (int ch = 0; ch < channels; ++ch)
                        for (int p = 0; p < height * width; ++p)
                            d.weights[static_cast<std::size_t>(o) * d.inputs_padded + p * c.out_padded + ch] =
                                raw[(static_cast<std::size_t>(o) * channels + ch) * height * width + p];
            } else {
                d.inputs_padded = roundUp8(d.inputs);
                d.weights.assign(static_cast<std::size_t>(d.outputs) * d.inputs_padded, 0.0f);
                for (int o = 0; o < d.outputs; ++o)
                    std::copy_n(raw.begin() + static_cast<std::ptrdiff_t>(o) * d.inputs, d.inputs,
                                d.weights.begin() + static_cast<std::ptrdiff_t>(o) * d.inputs_padded);
            }
            d.bias.assign(static_cast<std::size_t>(d.outputs), 0.0f);
            if (layer->blobs.size() > 1 && !readFloats(layer->blobs[1], static_cast<std::size_t>(d.outputs), d.bias))
                return fail("dense layer " + name + "'s bias does not match its outputs");
            L.denses.push_back(std::move(d));
            lastIsConv = false;
        } else if (type == "Softmax") {
            const auto softmax = layer.dynamicCast<cv::dnn::SoftmaxLayer>();
            if (!softmax || softmax->logSoftMax || flat || !lastIsConv || L.softmax)
                return fail("softmax " + name + " does not follow the last convolution");
            L.softmax = true;
        } else if (type != "Identity" && type != "Dropout") {
            return fail("layer " + name + " is a " + type + ", which the chain does not run");
        }
        if (L.softmax && type != "Softmax" && type != "Identity" && type != "Dropout")
            return fail("layer " + name + " follows the softmax");
    }
    if (L.convs.empty()) return fail("the net has no convolution");
    L.outputs_per_item = L.denses.empty() ? channels * height * width : L.denses.back().outputs;
    for (const Conv& c : L.convs)
        L.activations.emplace_back(
            static_cast<std::size_t>((c.in_h + c.pad_top + c.pad_bottom) * (c.in_w + c.pad_left + c.pad_right)) * c.in_padded, 0.0f);
    const Conv& last = L.convs.back();
    L.activations.emplace_back(static_cast<std::size_t>(L.batch) * last.out_h * last.out_w * last.out_padded, 0.0f);
    for (const Dense& d : L.denses) L.dense_floats = std::max({L.dense_floats, d.inputs_padded, roundUp8(d.outputs)});
    L.dense_in.assign(static_cast<std::size_t>(L.batch) * L.dense_floats, 0.0f);
    L.dense_out.assign(static_cast<std::size_t>(L.batch) * L.dense_floats, 0.0f);
    return ConvChain(std::move(L));
}

ConvChain::ConvChain(Layers layers) : layers_(std::move(layers)) {
#ifdef FACETRACK_CONV_CHAIN_AVX2
    avx2_ = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#endif
}

void ConvChain::forward(const float* in, float* out) {
#ifdef FACETRACK_CONV_CHAIN_AVX2
    if (avx2_) {
        runChainAvx2(layers_, in, out);
        return;
    }
#endif
    forwardPortable(in, out);
}

void ConvChain::forwardPortable(const float* in, float* out) { runChainGeneric(layers_, in, out); }

}  // namespace facetrack::nn
