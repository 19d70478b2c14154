// train_convention: learns where each 300-W landmark sits on the face model
// (docs/expressions.md). The face model's 68 landmark vertices follow another
// annotation convention than 300-W's annotators; the fit then explains the
// difference with expressions (a relaxed face reads as a sneer). Fitting the
// 300-W training faces with pose only (expressions held near 0 by a strong
// prior), each landmark's median residual, moved back onto the face at its
// depth, is that landmark's offset, averaged with its mirror landmark's; three
// rounds. Jaw landmarks (0-16) slide along the silhouette and are left alone.
//
// With --dense-labels (label_dense's output), also the
// expression prior: per fitted shape f_j = s g / E[b_j^2], E over the dense
// teacher labels of the training crops and clips (L/R averaged; g their
// geometric mean), and the strength s the one whose fits of the 300-W
// training faces' annotated landmarks come closest to those faces' dense
// labels; then each mirror pair's factor times 1/4, 1/2, 2 or 4 by the same
// criterion (two sweeps of coordinate descent: a shape the points observe well,
// as the smile, needs less pull than its spread alone says). The eye shapes keep 1:
// the gaze stage owns them.
//
//   build/tools/train_convention --out models/landmark_convention.ftm [--dense-labels build/dense_labels]

#include "app/args.hpp"
#include "common/faces300w.hpp"
#include "data/dense/label_table.hpp"

#include "core/camera.hpp"
#include "core/pts.hpp"
#include "facetrack/facetrack.hpp"
#include "fit/face_fitter.hpp"
#include "fit/fit_basis.hpp"
#include "model/internals.hpp"
#include "model/landmark_convention.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

using namespace facetrack;

namespace {

struct Face {
    std::string key;  ///< path relative to the 300-W folder
    core::Camera camera;
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
        f.key = std::filesystem::relative(a.image, root).string();
        f.camera = core::cameraFor(image.cols, image.rows, 60.0, 0.0);
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

/// label_dense's rows of one split, as column name -> value, keyed by the row's key.
std::map<std::string, std::map<std::string, double>> readDenseLabelsOfSplit(const std::string& path, const std::string& split) {
    const dense::LabelTable table = dense::readLabelTable(path);
    std::map<std::string, std::map<std::string, double>> rows;
    for (const auto& r : table.rows) {
        if (r.split != split) continue;
        auto& row = rows[r.key];
        for (std::size_t k = 0; k < table.columns.size(); ++k) row[table.columns[k]] = r.values[k];
    }
    return rows;
}

std::map<std::string, std::map<std::string, double>> readDenseLabels(const std::string& path) {
    return readDenseLabelsOfSplit(path, "train");
}

/// Mean squared difference between the fits of `faces` and their dense labels, over the non-eye fitted shapes.
double labelError(const std::shared_ptr<const fit::FitBasis>& basis, const std::vector<std::string>& names, const std::vector<Face>& faces,
                  const std::map<std::string, std::map<std::string, double>>& labels) {
    fit::FaceFitter fitter(basis, fit::FitSettings());
    double sum = 0.0;
    long n = 0;
    for (const Face& f : faces) {
        const auto label = labels.find(f.key);
        if (label == labels.end()) continue;
        fit::FaceParams p;
        fitter.fit(f.camera, f.observed, p, false);
        for (std::size_t k = 0; k < names.size(); ++k) {
            if (names[k].rfind("eye", 0) == 0) continue;
            const double d = p.expression[static_cast<Eigen::Index>(k)] - label->second.at(names[k]);
            sum += d * d;
            ++n;
        }
    }
    return n ? sum / static_cast<double>(n) : std::nan("");
}

double median(std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const tools::Args args(std::vector<std::string>(argv + 1, argv + argc), {"--out", "--rounds", "--dense-labels"}, {"--help"});
        if (args.has("--help")) {
            std::puts("usage: train_convention [--out models/landmark_convention.ftm] [--rounds 3] [--dense-labels DIR]");
            return 0;
        }
        const auto model = FaceModel::load(FaceModel::defaultPath());  // the bare model: no convention yet
        const std::string root = tools::faces300wRoot("");
        const auto train = loadFaces(root, tools::Split::Train);
        const auto validation = loadFaces(root, tools::Split::Validation);
        std::printf("300-W: %zu training, %zu validation faces\n", train.size(), validation.size());

        fit::FitBasis basis = *fit::basisOf(model);
        fit::FitSettings poseOnly;
        poseOnly.expression_l2 = 1.0;  // expressions held near 0: the residual is the convention
        model::LandmarkConvention convention;
        const int rounds = args.integer("--rounds", 3);
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
        if (args.has("--dense-labels")) {
            const std::string dir = args.get("--dense-labels");
            const auto labels = readDenseLabels(dir + "/faces300w.csv");
            const auto clipLabels = readDenseLabels(dir + "/clips.csv");
            const auto names = basis.expressionNames(model::dataOf(*model));
            std::vector<double> moment(names.size(), 0.0);
            for (const auto* set : {&labels, &clipLabels})
                for (const auto& [key, row] : *set)
                    for (std::size_t k = 0; k < names.size(); ++k)
                        moment[k] += std::pow(row.at(names[k]), 2) / static_cast<double>(labels.size() + clipLabels.size());
            std::vector<double> symmetric(names.size());
            std::vector<std::size_t> partner(names.size());  // the mirror shape's index; its own for a centred shape
            double logMean = 0.0;
            int counted = 0;
            for (std::size_t k = 0; k < names.size(); ++k) {
                const std::string mirror = fit::mirrorName(names[k]);
                partner[k] = static_cast<std::size_t>(std::find(names.begin(), names.end(), mirror.empty() ? names[k] : mirror) -
                                                      names.begin());
                symmetric[k] = std::max(1e-4, 0.5 * (moment[k] + moment[partner[k]]));
                if (names[k].rfind("eye", 0) == 0) continue;
                logMean += std::log(symmetric[k]);
                ++counted;
            }
            const double g = std::exp(logMean / counted);
            std::printf("expression prior from %zu + %zu labelled training crops and frames (dense teacher labels, not truth):\n",
                        labels.size(), clipLabels.size());
            const auto flat = std::make_shared<const fit::FitBasis>(basis);
            const auto errorWith = [&](const std::vector<double>& factor) {
                fit::FitBasis b = basis;
                for (std::size_t k = 0; k < names.size(); ++k) b.expression_prior[static_cast<Eigen::Index>(k)] = factor[k];
                return labelError(std::make_shared<const fit::FitBasis>(b), names, train, labels);
            };
            const auto spreadFactors = [&](double strength) {  // f_j = s g / E[b_j^2]; the eye shapes keep 1
                std::vector<double> factor(names.size(), 1.0);
                for (std::size_t k = 0; k < names.size(); ++k)
                    if (names[k].rfind("eye", 0) != 0) factor[k] = strength * g / symmetric[k];
                return factor;
            };
            double bestStrength = 0.0, bestError = labelError(flat, names, train, labels);
            std::printf("  flat prior: mean squared difference to the labels on the training faces %.4f\n", bestError);
            for (const double strength : {1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0}) {
                const double error = errorWith(spreadFactors(strength));
                std::printf("  strength %5.0f: %.4f\n", strength, error);
                if (error < bestError) bestError = error, bestStrength = strength;
            }
            std::printf("  chosen strength %.0f (0: the flat prior)\n", bestStrength);
            if (bestStrength > 0.0) {
                std::vector<double> factor = spreadFactors(bestStrength);
                // Then each mirror pair's factor in turn, the others held: the one whose fits come closest.
                for (int sweep = 0; sweep < 2; ++sweep)
                    for (std::size_t k = 0; k < names.size(); ++k) {
                        if (names[k].rfind("eye", 0) == 0 || partner[k] < k) continue;
                        const double start = factor[k];
                        for (const double m : {0.25, 0.5, 2.0, 4.0}) {
                            std::vector<double> trial = factor;
                            trial[k] = trial[partner[k]] = start * m;
                            const double error = errorWith(trial);
                            if (error < bestError) bestError = error, factor = trial;
                        }
                        std::printf("  sweep %d %-16s factor %.2f -> %.2f: %.4f\n", sweep + 1, names[k].c_str(), start, factor[k],
                                    bestError);
                    }
                for (std::size_t k = 0; k < names.size(); ++k) {
                    if (names[k].rfind("eye", 0) == 0) continue;
                    convention.expression_prior[names[k]] = factor[k];
                    basis.expression_prior[static_cast<Eigen::Index>(k)] = factor[k];
                    std::printf("  %-16s E[b^2] %.4f  factor %.2f\n", names[k].c_str(), symmetric[k], factor[k]);
                }
            }
            std::printf("  300-W validation: flat %.4f, chosen %.4f\n",
                        labelError(flat, names, validation, readDenseLabelsOfSplit(dir + "/faces300w.csv", "validation")),
                        labelError(std::make_shared<const fit::FitBasis>(basis), names, validation,
                                   readDenseLabelsOfSplit(dir + "/faces300w.csv", "validation")));
        }
        // What it changes on held-out faces, with the tracker's own fit settings.
        const fit::FitSettings settings;
        Eigen::VectorXd before, after;
        const double rBefore = fitAll(fit::basisOf(model), settings, validation, nullptr, &before);
        const double rAfter = fitAll(std::make_shared<const fit::FitBasis>(basis), settings, validation, nullptr, &after);
        std::printf("300-W validation, tracker's fit: residual %.4f -> %.4f; mean expression weights (before -> after):\n", rBefore,
                    rAfter);
        const auto names = fit::basisOf(model)->expressionNames(model::dataOf(*model));
        for (int k = 0; k < basis.expressionCount(); ++k)
            std::printf("  %-18s %.3f -> %.3f\n", names[static_cast<std::size_t>(k)].c_str(), before[k], after[k]);
        const std::string out = args.get("--out", "models/landmark_convention.ftm");
        model::writeLandmarkConvention(out, convention);
        std::printf("wrote %s\n", out.c_str());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "train_convention: %s\n", e.what());
        return 1;
    }
}
