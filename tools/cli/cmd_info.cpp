#include "commands.hpp"

#include "facetrack/facetrack.hpp"

#include <algorithm>
#include <cstdio>

namespace facetrack::cli {

int runInfo(const std::vector<std::string>& argv) {
    const Args args(argv, trackingOptions({}), trackingFlags({"--help"}));
    if (args.has("--help")) {
        std::puts(
            "usage: facetrack info [tracker options]\n"
            "Prints the version, the models in use, the tracker's pipeline stages and which ARKit shapes it\n"
            "estimates, as a tracker with these options (e.g. --cnn none, --no-cnn-stage, --eyes none) would run.");
        return 0;
    }
    if (!args.positional().empty()) throw Error("info takes no arguments");
    const TrackerConfig config = trackerConfig(args);
    const Models models = trackingModels(args);
    setLogHandler({});
    std::printf("facetrack %s\n", versionString());
    std::printf("model directory: %s\n", modelDirectory().c_str());

    const auto& model = models.face;
    std::printf("face model: %s (format v%u)\n", model->sourcePath().c_str(), FaceModel::formatVersion());
    std::printf("  %d vertices, %d triangles, %d identity modes (%.1f%% of face-region variance), %zu expressions\n", model->vertexCount(),
                model->triangleCount(), model->identityCount(), 100.0 * model->identityExplainedVariance(),
                model->expressionNames().size());
    std::printf("  output: ARKit-%d blendshapes (tongueOut unsupported, always 0; which are estimated: below)\n", kArkitBlendshapeCount);
    std::printf("  landmark convention: %s\n",
                model->conventionPath().empty() ? "none (the model's own landmark vertices)" : model->conventionPath().c_str());

    if (models.landmarks) {
        std::printf("landmark model: %s (format v%u)\n  LBF, %d stages, %d trees of depth %d per landmark\n",
                    models.landmarks->sourcePath().c_str(), LandmarkModel::formatVersion(), models.landmarks->stageCount(),
                    models.landmarks->treesPerLandmark(), models.landmarks->treeDepth());
    } else {
        std::printf("landmark model: not found in %s\n", modelDirectory().c_str());
    }

    const Tracker tracker(models, config);
    std::puts("stages:");
    for (const auto& stage : tracker.stages()) {
        std::printf("  %-10s %s\n", stage.name.c_str(), stage.detail.c_str());
    }
    const auto estimated = tracker.estimatedShapes();
    std::printf("ARKit shapes estimated (%zu of %d):", estimated.size(), kArkitBlendshapeCount);
    for (const auto& name : estimated) std::printf(" %s", name.c_str());
    std::printf("\nalways 0 with these models:");
    for (const auto& name : arkitNames())
        if (std::find(estimated.begin(), estimated.end(), name) == estimated.end()) std::printf(" %s", std::string(name).c_str());
    std::printf("\n");
    return 0;
}

}  // namespace facetrack::cli
