// pack_refiner: the refine stage's model file (facetrack/refiner_model.hpp) from the ONNX exports
// of tools/train/refine (docs/landmarks.md).
//
//   build/tools/pack_refiner [--refiner build/refine/net.onnx] [--sides build/region/net.onnx] [--base FILE.ftm]
//                            --out models/landmark_refiner.ftm [--provenance "..."]
//
// --refiner: the landmark refiner of train_refine.py (refine/landmark_refiner.hpp), with its
// NET.refiner.txt beside it (the patch size, the 136 mean-shape values, the 68 shares and, when the
// trainer chose them, the trust ramp D0 D1). --sides: the brow and eye refiner of
// train_region.py (one side at a time), with its NET.side.txt beside it (the patch size, the 22
// mean-shape values and the 11 shares). --base: start from that file (the nets given replace its
// own). Each net is run once to check that it loads and gives its outputs.

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "core/binary_io.hpp"
#include "nn/patch_net.hpp"
#include "nn/refiner_model_data.hpp"

#include <cstdio>
#include <sstream>

using namespace facetrack;

namespace {

std::string readBytes(const std::string& path) { return core::readFileBytes(path, "'" + path + "'"); }

/// The net at `path` and its layout file NET.SUFFIX beside it: the patch size, `points` mean-shape
/// points (x0, y0, x1, ...) and a share each; the stream is left after them.
std::stringstream readNet(const std::string& path, const std::string& suffix, std::size_t points, std::string& net, int& size,
                          std::vector<float>& mean, std::vector<float>& share) {
    net = readBytes(path);
    const std::string stem = path.size() > 5 && path.substr(path.size() - 5) == ".onnx" ? path.substr(0, path.size() - 5) : path;
    std::stringstream layout(readBytes(stem + suffix));
    layout >> size;
    mean.resize(2 * points);
    share.resize(points);
    for (float& v : mean) layout >> v;
    for (float& v : share) layout >> v;
    if (!layout) {
        throw Error(path + ": its " + suffix + " needs the patch size, " + std::to_string(2 * points) + " mean-shape values and " +
                    std::to_string(points) + " shares");
    }
    nn::PatchNet check(net, size, static_cast<int>(2 * points), path);
    return layout;
}

int run(int argc, char** argv) {
    const tools::Args args(std::vector<std::string>(argv + 1, argv + argc), {"--refiner", "--sides", "--base", "--out", "--provenance"},
                           {"--help"});
    if (args.has("--help") || !(args.has("--refiner") || args.has("--base")) || !args.has("--out")) {
        std::puts("usage: pack_refiner [--refiner R.onnx] [--sides S.onnx] [--base FILE.ftm] --out FILE.ftm [--provenance TEXT]");
        return args.has("--help") ? 0 : 2;
    }
    nn::RefinerModelData model;
    if (args.has("--base")) model = nn::readRefinerModel(args.get("--base"));
    model.provenance = args.get("--provenance", model.provenance);
    if (args.has("--refiner")) {
        const std::string path = args.get("--refiner");
        std::stringstream rest = readNet(path, ".refiner.txt", 68, model.net, model.patch_size, model.mean, model.share);
        float from = 0.f, to = 0.f;
        model.trust_from = model.trust_to = 0.f;
        if (rest >> from >> to) model.trust_from = from, model.trust_to = to;
        std::printf("landmark refiner: %s, %d px, %zu bytes, trust ramp %.3f-%.3f\n", path.c_str(), model.patch_size, model.net.size(),
                    model.trust_from, model.trust_to);
    }
    if (args.has("--sides")) {
        const std::string path = args.get("--sides");
        readNet(path, ".side.txt", 11, model.side_net, model.side_patch_size, model.side_mean, model.side_share);
        std::printf("brow and eye refiner: %s, %d px, %zu bytes\n", path.c_str(), model.side_patch_size, model.side_net.size());
    }
    nn::writeRefinerModel(args.get("--out"), model);
    std::printf("wrote %s\n", args.get("--out").c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("pack_refiner", run, argc, argv); }
