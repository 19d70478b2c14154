// train_convention: learns where each 300-W landmark sits on the face model
// (issue 16, step 2). The face model's 68 landmark vertices follow another
// annotation convention than 300-W's annotators; the fit then explains the
// difference with expressions (a relaxed face reads as a sneer). Fitting the
// 300-W training faces with pose only (expressions held near 0 by a strong
// prior), each landmark's median residual, moved back onto the face at its
// depth, is that landmark's offset, averaged with its mirror landmark's; three
// rounds. Jaw landmarks (0-16) slide along the silhouette and are left alone.
//
//   build/tools/train_convention --out models/landmark_convention.ftm

#include "app/args.hpp"
#include "common/faces300w.hpp"

#include "core/pts.hpp"
#include "fit/camera.hpp"
#include "fit/face_fitter.hpp"
#include "fit/fit_basis.hpp"
#include "fit/landmark_convention.hpp"
#include "facetrack/facetrack.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>

using namespace facetrack;

namespace {

struct Face {
    fit::Camera camera;
    fit::Landmarks2d observed;
};

std::vector<Face> loadFaces(const std::string& root, tools::Split split) {
    std::vector<Face> faces;
    for (const auto& a : tools::list300W(root, split)) {
        const cv::Mat image = cv::imread(a.image, cv::IMREAD_GRAYSCALE);
        if (image.empty()) continue;
        const core::Shape2 pts = core::readPts(a.pts);
        if (pts.cols() != model::kLandmarkCount) continue;
        Face f;
        f.camera = fit::cameraFor(image.cols, image.rows, 60.0, 0.0);
        f.observed = pts.cast<double>();
        faces.push_back(f);
    }
    return faces;
}

/// Fits every face; returns the mean residual (eye-corner distances) and, when
/// `displacements` is given, each landmark's residual moved onto the face (frontal frame, cm).
double fitAll(const std::shared_ptr<const fit::FitBasis>& basis, const fit::FitSettings& settings, const std::vector<Face>& faces,
              std::vector<std::vector<Eigen::Vector3d>>* displacements, Eigen::VectorXd* meanExpression) {
    fit::FaceFitter fitter(basis, settings);
    double residual = 0.0;
    if (meanExpression) *meanExpression = Eigen::VectorXd::Zero(basis->expressionCount());
    Eigen::Matrix3Xd x;
    for (const Face& f : faces) {
        fit::FaceParams p;
        const fit::FitReport r = fitter.fit(f.camera, f.observed, p, false);
        residual += r.residual / static_cast<double>(faces.size());
        if (meanExpression) *meanExpression += p.expression / static_cast<double>(faces.size());
        if (!displacements) continue;
        fit::slotPositions(*basis, fitter.base(), p.expression, x);
        const Eigen::Matrix3d R = fit::rotationOf(p.pose.head<3>());
        for (int i = model::kContourLandmarkCount; i < model::kLandmarkCount; ++i) {
            const Eigen::Vector3d P = R * x.col(basis->landmark_slots[static_cast<std::size_t>(i)]) + p.pose.tail<3>();
            const Eigen::Vector2d d = f.observed.col(i) - r.projected.col(i);
            const Eigen::Vector3d inCamera(d.x() * P.z() / f.camera.fx, d.y() * P.z() / f.camera.fy, 0.0);
            (*displacements)[static_cast<std::size_t>(i)].push_back(R.transpose() * inCamera);
        }
    }
    return residual;
}

double median(std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const tools::Args args(std::vector<std::string>(argv + 1, argv + argc), {"--out", "--rounds"}, {"--help"});
        if (args.has("--help")) {
            std::puts("usage: train_convention [--out models/landmark_convention.ftm] [--rounds 3]");
            return 0;
        }
        const auto model = FaceModel::load(FaceModel::defaultPath());  // the bare model: no convention yet
        const std::string root = tools::faces300wRoot("");
        const auto train = loadFaces(root, tools::Split::Train);
        const auto validation = loadFaces(root, tools::Split::Validation);
        std::printf("300-W: %zu training, %zu validation faces\n", train.size(), validation.size());

        fit::FitBasis basis = *model->fitBasis();
        fit::FitSettings poseOnly;
        poseOnly.expression_l2 = 1.0;  // expressions held near 0: the residual is the convention
        fit::LandmarkConvention convention;
        const int rounds = static_cast<int>(args.number("--rounds", 3));
        for (int round = 0; round < rounds; ++round) {
            std::vector<std::vector<Eigen::Vector3d>> displacements(model::kLandmarkCount);
            const double residual = fitAll(std::make_shared<const fit::FitBasis>(basis), poseOnly, train, &displacements, nullptr);
            Eigen::Matrix<double, 3, model::kLandmarkCount> step = Eigen::Matrix<double, 3, model::kLandmarkCount>::Zero();
            for (int i = model::kContourLandmarkCount; i < model::kLandmarkCount; ++i) {
                const auto& d = displacements[static_cast<std::size_t>(i)];
                for (int c = 0; c < 3; ++c) {
                    std::vector<double> values;
                    for (const auto& v : d) values.push_back(v[c]);
                    step(c, i) = median(values);
                }
            }
            // The annotation convention is symmetric: each offset is averaged with its mirror
            // landmark's, x negated (the frontal frame's x is the model's).
            double moved = 0.0;
            for (int i = model::kContourLandmarkCount; i < model::kLandmarkCount; ++i) {
                Eigen::Vector3d mirror = step.col(tools::kMirror68[static_cast<std::size_t>(i)]);
                mirror.x() = -mirror.x();
                const Eigen::Vector3d m = 0.5 * (step.col(i) + mirror);
                basis.neutral.col(basis.landmark_slots[static_cast<std::size_t>(i)]) += m;
                convention.offsets_frontal_cm.col(i) += m;
                moved = std::max(moved, m.norm());
            }
            std::printf("round %d: pose-only residual before %.4f eye-corner distances; largest offset change %.2f mm\n", round + 1,
                        residual, 10.0 * moved);
        }
        // What it changes on held-out faces, with the tracker's own fit settings.
        const fit::FitSettings settings;
        Eigen::VectorXd before, after;
        const double rBefore = fitAll(model->fitBasis(), settings, validation, nullptr, &before);
        const double rAfter = fitAll(std::make_shared<const fit::FitBasis>(basis), settings, validation, nullptr, &after);
        std::printf("300-W validation, tracker's fit: residual %.4f -> %.4f; mean expression weights (before -> after):\n", rBefore, rAfter);
        const auto names = model->fitBasis()->expressionNames(model->data());
        for (int k = 0; k < basis.expressionCount(); ++k)
            std::printf("  %-18s %.3f -> %.3f\n", names[static_cast<std::size_t>(k)].c_str(), before[k], after[k]);
        const std::string out = args.get("--out", "models/landmark_convention.ftm");
        fit::writeLandmarkConvention(out, convention);
        std::printf("wrote %s\n", out.c_str());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "train_convention: %s\n", e.what());
        return 1;
    }
}
