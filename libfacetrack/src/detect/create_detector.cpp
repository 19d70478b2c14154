#include "core/environment.hpp"
#include "detect/cascade_detector.hpp"
#include "detect/yunet_detector.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/error.hpp"
#include "facetrack/version.hpp"

namespace facetrack {

namespace {
constexpr char kYuNetFile[] = "face_detection_yunet_2022mar.onnx";
constexpr char kDefaultCascade[] = "/usr/share/opencv4/haarcascades/haarcascade_frontalface_alt2.xml";

/// An explicitly named file that does not exist is an error, not a reason to fall back.
std::string requireFile(const std::string& path, const std::string& origin) {
    if (core::firstExistingFile({path}).empty()) {
        throw Error("YuNet model '" + path + "' (from " + origin + ") does not exist");
    }
    return path;
}
}  // namespace

std::string findYuNetModel(const DetectorConfig& config) {
    if (!config.yunet_model.empty()) return requireFile(config.yunet_model, "DetectorConfig::yunet_model");
    const std::string fromEnv = core::getEnv("FACETRACK_YUNET_MODEL");
    if (!fromEnv.empty()) return requireFile(fromEnv, "FACETRACK_YUNET_MODEL");
    const std::string shared = core::sharedDirectory();
    return core::firstExistingFile({
        modelDirectory() + "/" + kYuNetFile,
        shared.empty() ? "" : shared + "/models/yunet/" + kYuNetFile,
    });
}

std::unique_ptr<FaceDetector> createFaceDetector(const DetectorConfig& config) {
    if (config.detect_width < 32) throw Error("DetectorConfig::detect_width must be at least 32");
    if (config.kind != DetectorKind::Cascade) {
        const std::string yunet = findYuNetModel(config);
        if (!yunet.empty()) {
            auto detector = std::make_unique<detect::YuNetDetector>(yunet, config);
            core::log("face detector: YuNet (" + yunet + ")");
            return detector;
        }
        if (config.kind == DetectorKind::YuNet) {
            throw Error(std::string("YuNet model not found: set FACETRACK_YUNET_MODEL or put ") + kYuNetFile + " in " + modelDirectory());
        }
    }
    const std::string cascade = config.cascade_file.empty() ? kDefaultCascade : config.cascade_file;
    auto detector = std::make_unique<detect::CascadeDetector>(cascade, config);
    core::log(std::string(config.kind == DetectorKind::Auto ? "YuNet model not found, falling back to " : "") +
              "face detector: OpenCV Haar cascade (" + cascade + ")");
    return detector;
}

}  // namespace facetrack
