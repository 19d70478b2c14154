#pragma once
/// \file
/// The CNN cascade of the "cnn" stage (thesis 4.4): small nets that regress,
/// from the face texture warped into a canonical patch at the current pose and
/// expression, the update to both, and optionally a last net that moves the
/// 68 landmarks from where the refined face projects them. Trained by tools/train/expression on the dense
/// teacher labels (MediaPipe's mesh fitted with the face model; docs/cnn.md), with a net that
/// reads the expressions from the landmarks' geometry beside them.
///
/// Like the other models it is data: load it once, it is immutable, share it
/// (by shared_ptr) between any number of Trackers on any threads.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace facetrack {

namespace nn {
struct CnnModelData;
}
namespace model {
struct Internals;
}

class CnnModel {
public:
    /// Throws facetrack::Error naming the file when it is missing, truncated,
    /// corrupt or of another format version.
    static std::shared_ptr<const CnnModel> load(const std::string& path);
    /// cnn_cascade.ftm in modelDirectory().
    static std::string defaultPath();
    static std::uint32_t formatVersion();

    const std::string& sourcePath() const;
    /// What it was trained on, as the packer wrote it.
    const std::string& provenance() const;
    /// Per stage, how many rounds it runs.
    std::vector<int> rounds() const;
    /// Whether it has the landmark net: the stage then reports its landmarks.
    bool hasLandmarkNet() const;
    /// Whether its nets read only the expressions: the stage then keeps the fit's
    /// pose and the shapes the fit estimates, and adds the others (docs/cnn.md).
    bool expressionsOnly() const;

private:
    friend struct model::Internals;  // facetrack's own stages read the data behind it
    CnnModel(std::shared_ptr<const nn::CnnModelData> data, std::string source);

    std::shared_ptr<const nn::CnnModelData> data_;
    std::string source_;
};

}  // namespace facetrack
