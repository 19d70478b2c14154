#include "commands.hpp"

namespace facetrack::cli {

DetectorConfig detectorConfig(const Args& args) {
    DetectorConfig config;
    const std::string kind = args.get("--detector", "auto");
    if (kind == "auto") config.kind = DetectorKind::Auto;
    else if (kind == "yunet") config.kind = DetectorKind::YuNet;
    else if (kind == "cascade") config.kind = DetectorKind::Cascade;
    else throw Error("--detector must be auto, yunet or cascade, not '" + kind + "'");
    config.yunet_model = args.get("--yunet");
    config.min_score = static_cast<float>(args.number("--min-score", config.min_score));
    if (!(config.min_score >= 0.f && config.min_score <= 1.f)) throw Error("--min-score must be in [0, 1]");
    return config;
}

}  // namespace facetrack::cli
