#include "app/tracking_options.hpp"

#include <cstdio>
#include <filesystem>

namespace facetrack::tools {

DetectorConfig detectorConfig(const Args& args) {
    DetectorConfig config;
    const std::string kind = args.get("--detector", "auto");
    if (kind == "auto") config.kind = DetectorKind::Auto;
    else if (kind == "yunet") config.kind = DetectorKind::YuNet;
    else if (kind == "cascade") config.kind = DetectorKind::Cascade;
    else throw Error("--detector must be auto, yunet or cascade, not '" + kind + "'");
    config.yunet_model = args.get("--yunet");
    std::error_code ec;
    if (!config.yunet_model.empty() && !std::filesystem::is_regular_file(config.yunet_model, ec)) {
        throw Error("--yunet: no file '" + config.yunet_model + "'");
    }
    config.min_score = static_cast<float>(args.number("--min-score", config.min_score));
    if (!(config.min_score >= 0.f && config.min_score <= 1.f)) throw Error("--min-score must be in [0, 1]");
    return config;
}

TrackerConfig trackerConfig(const Args& args) {
    TrackerConfig config;
    config.detector = detectorConfig(args);
    config.max_faces = args.integer("--max-faces", config.max_faces);
    config.camera.horizontal_fov_deg = args.number("--fov", config.camera.horizontal_fov_deg);
    config.camera.focal_length_px = args.number("--focal", config.camera.focal_length_px);
    // The API reads any focal length <= 0 as "from the field of view"; a negative one typed here is a mistake.
    if (config.camera.focal_length_px < 0.0) throw Error("--focal must be pixels, or 0 for the field of view (--fov)");
    config.calibration_frames = args.integer("--calibration-frames", config.calibration_frames);
    config.expression_prior = static_cast<float>(args.number("--expression-prior", config.expression_prior));
    config.landmark_starts = args.integer("--landmark-starts", config.landmark_starts);
    config.filter.enabled = !args.has("--no-filter");
    config.cnn_stage = !args.has("--no-cnn-stage");
    config.filter.min_cutoff_hz = args.number("--filter-cutoff", config.filter.min_cutoff_hz);
    config.filter.beta = args.number("--filter-beta", config.filter.beta);
    if (!(config.filter.min_cutoff_hz > 0.0) || !(config.filter.beta >= 0.0)) {
        throw Error("--filter-cutoff must be positive and --filter-beta not negative");
    }
    validate(config);
    return config;
}

Models trackingModels(const Args& args) {
    Models models = Models::loadDefault();
    if (args.has("--refiner")) {
        const std::string refiner = args.get("--refiner");
        models.refiner = refiner == "none" ? nullptr : RefinerModel::load(refiner);
    }
    if (args.has("--cnn")) {
        const std::string cnn = args.get("--cnn");
        models.cnn = cnn == "none" ? nullptr : CnnModel::load(cnn);
    }
    if (args.has("--eyes")) {
        const std::string eyes = args.get("--eyes");
        models.eyes = eyes == "none" ? nullptr : EyeModel::load(eyes);
    }
    return models;
}

Calibration userCalibration(const Args& args) {
    const std::string given = args.get("--profile");
    if (given == "none") return {};
    const std::string path = given.empty() ? defaultProfilePath() : given;
    std::error_code ec;
    if (given.empty() && !std::filesystem::exists(path, ec)) return {};
    Calibration calibration = loadCalibration(path);
    std::fprintf(stderr, "facetrack: calibration profile %s\n", path.c_str());
    return calibration;
}

std::set<std::string> trackingOptions(std::set<std::string> more) {
    more.insert(kDetectorOptions.begin(), kDetectorOptions.end());
    more.insert(kTrackerOptions.begin(), kTrackerOptions.end());
    return more;
}

std::set<std::string> trackingFlags(std::set<std::string> more) {
    more.insert(kTrackerFlags.begin(), kTrackerFlags.end());
    return more;
}

}  // namespace facetrack::tools
