#include "landmarks/lbf_trainer.hpp"

#include "core/shape2d.hpp"
#include "facetrack/error.hpp"
#include "landmarks/lbf.hpp"

#include <Eigen/LU>

#include <opencv2/imgproc.hpp>

#include <atomic>
#include <mutex>
#include <numbers>
#include <random>
#include <thread>

namespace facetrack::landmarks {

namespace {

using Targets = Eigen::Matrix<float, Eigen::Dynamic, 2 * kLandmarks, Eigen::RowMajor>;

/// Runs job(i) for i in [0, count) on `threads` threads.
template <class Job>
void parallelFor(int count, int threads, Job&& job) {
    std::atomic<int> next{0};
    auto worker = [&] {
        for (int i = next++; i < count; i = next++) job(i);
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
}

std::uint64_t mix(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
    std::uint64_t h = a * 0x9E3779B97F4A7C15ull ^ (b + 0x7F4A7C159E3779B9ull) * 0xBF58476D1CE4E5B9ull;
    h ^= (c + 1) * 0x94D049BB133111EBull;
    return h ^ (h >> 31);
}

struct Triangle {
    std::array<int, 3> anchors;
};

/// Delaunay triangles over the mean shape's anchors: they tile the padded hull.
std::vector<Triangle> triangulateAnchors(const Anchors& anchors) {
    const Eigen::Vector2f lo = anchors.rowwise().minCoeff(), hi = anchors.rowwise().maxCoeff();
    const float margin = 0.1f * (hi - lo).maxCoeff() + 1.f;
    // Subdiv2D works in float pixels: scale the unit-size mean shape up.
    constexpr float kScale = 1000.f;
    cv::Subdiv2D subdiv(cv::Rect(static_cast<int>((lo.x() - margin) * kScale), static_cast<int>((lo.y() - margin) * kScale),
                                 static_cast<int>((hi.x() - lo.x() + 2 * margin) * kScale),
                                 static_cast<int>((hi.y() - lo.y() + 2 * margin) * kScale)));
    for (Eigen::Index i = 0; i < anchors.cols(); ++i) subdiv.insert(cv::Point2f(anchors(0, i) * kScale, anchors(1, i) * kScale));
    std::vector<cv::Vec6f> list;
    subdiv.getTriangleList(list);
    std::vector<Triangle> triangles;
    for (const auto& t : list) {
        Triangle tri;
        bool ok = true;
        for (int k = 0; k < 3 && ok; ++k) {
            const Eigen::Vector2f p(t[2 * k] / kScale, t[2 * k + 1] / kScale);
            Eigen::Index nearest = 0;
            const float d = (anchors.colwise() - p).colwise().squaredNorm().minCoeff(&nearest);
            ok = d < 1e-6f;
            tri.anchors[k] = static_cast<int>(nearest);
        }
        if (ok) triangles.push_back(tri);
    }
    return triangles;
}

/// Barycentric (w0, w1, w2) of p in triangle abc.
Eigen::Vector3f barycentric(const Eigen::Vector2f& p, const Eigen::Vector2f& a, const Eigen::Vector2f& b, const Eigen::Vector2f& c) {
    Eigen::Matrix2f m;
    m << a - c, b - c;
    const Eigen::Vector2f w = m.inverse() * (p - c);
    return {w.x(), w.y(), 1.f - w.x() - w.y()};
}

/// One tree while it is grown: splits over pool indices, for the training table.
struct PoolSplit {
    int a = 0, b = 0;
    int threshold = 256;  // 256: every difference goes left
};

}  // namespace

LbfModel prepareLbfModel(const std::vector<TrainingImage>& images, const LbfTrainingOptions& options) {
    if (images.empty()) throw Error("no training images");
    if (options.trees_per_landmark < 1 || options.trees_per_landmark > 64) throw Error("trees per landmark must be 1..64");
    if (options.tree_depth < 1 || options.tree_depth > 12) throw Error("tree depth must be 1..12");
    std::vector<core::Shape2> shapes;
    for (const auto& im : images) shapes.emplace_back(im.truth);
    LbfModel model;
    model.trees_per_landmark = options.trees_per_landmark;
    model.tree_depth = options.tree_depth;
    model.hull_padding = options.hull_padding;
    model.mean_shape = core::procrustesMean(shapes);
    std::vector<cv::Point2f> points;
    for (int i = 0; i < kLandmarks; ++i) points.emplace_back(model.mean_shape(0, i), model.mean_shape(1, i));
    std::vector<int> hull;
    cv::convexHull(points, hull, false, false);
    for (int h : hull) model.hull_indices.push_back(static_cast<std::uint8_t>(h));
    return model;
}

std::vector<FeaturePoint> sampleFeaturePool(const LbfModel& model, int landmark, float radius, int count, std::uint64_t seed) {
    const Anchors anchors = anchorsOf(model, model.mean_shape);
    const auto triangles = triangulateAnchors(anchors);
    std::vector<cv::Point2f> hullPoints;
    for (Eigen::Index i = 0; i < anchors.cols(); ++i) hullPoints.emplace_back(anchors(0, i), anchors(1, i));
    std::vector<cv::Point2f> hull;
    cv::convexHull(hullPoints, hull);
    const float unit = (model.mean_shape.col(36) - model.mean_shape.col(45)).norm();

    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> uniform(0.f, 1.f);
    std::vector<FeaturePoint> pool;
    for (int attempt = 0; static_cast<int>(pool.size()) < count && attempt < 100 * count; ++attempt) {
        const float angle = 2.f * std::numbers::pi_v<float> * uniform(rng);
        const float rho = radius * unit * std::sqrt(uniform(rng));
        const Eigen::Vector2f p = model.mean_shape.col(landmark) + rho * Eigen::Vector2f(std::cos(angle), std::sin(angle));
        if (cv::pointPolygonTest(hull, cv::Point2f(p.x(), p.y()), false) < 0) continue;
        for (const auto& t : triangles) {
            const Eigen::Vector3f w = barycentric(p, anchors.col(t.anchors[0]), anchors.col(t.anchors[1]), anchors.col(t.anchors[2]));
            if (w.minCoeff() < -1e-5f) continue;
            FeaturePoint f;
            for (int k = 0; k < 3; ++k) f.anchors[k] = static_cast<std::uint8_t>(t.anchors[k]);
            f.weights = {w.x(), w.y()};
            pool.push_back(f);
            break;
        }
    }
    if (pool.size() < 2) throw Error("cannot sample feature points around landmark " + std::to_string(landmark));
    return pool;
}

void trainLbfStage(LbfModel& model, const std::vector<TrainingImage>& images, std::vector<TrainingSample>& samples,
                   const LbfTrainingOptions& o) {
    const int stageIndex = static_cast<int>(model.stages.size());
    const float radius = o.radii.at(std::min<std::size_t>(stageIndex, o.radii.size() - 1));
    const int n = static_cast<int>(samples.size());
    const int treesPerLandmark = model.trees_per_landmark;
    const int trees = model.treesPerStage(), leaves = model.leavesPerTree(), splitsPerTree = model.splitsPerTree();
    auto report = [&, mutex = std::make_shared<std::mutex>()](const std::string& what, double done) {
        if (!o.progress) return;
        std::lock_guard<std::mutex> lock(*mutex);
        o.progress("stage " + std::to_string(stageIndex + 1) + ": " + what, done);
    };

    // Regression targets: the remaining increment, in each sample's mean-shape frame.
    Targets targets(n, 2 * kLandmarks);
    std::vector<Anchors> anchors(n);
    parallelFor(n, o.threads, [&](int i) {
        const auto& s = samples[i];
        const Eigen::Matrix2f toMean = core::alignSimilarity(s.shape, model.mean_shape).linear();
        const Shape68 delta = toMean * (images[s.image].truth - s.shape);
        targets.row(i) = Eigen::Map<const Eigen::Matrix<float, 1, 2 * kLandmarks>>(delta.data());
        anchors[i] = anchorsOf(model, s.shape);
    });

    // Local forests: each landmark's trees, grown on its own 2D increment.
    LbfStage stage;
    stage.splits.resize(static_cast<std::size_t>(trees) * splitsPerTree);
    std::vector<int> leafOf(static_cast<std::size_t>(n) * trees);
    std::atomic<int> landmarksDone{0};
    parallelFor(kLandmarks, o.threads, [&](int l) {
        std::mt19937_64 rng(mix(o.seed, stageIndex, l));
        const auto pool = sampleFeaturePool(model, l, radius, o.pool_size, rng());
        const int poolSize = static_cast<int>(pool.size());
        std::vector<std::uint8_t> intensity(static_cast<std::size_t>(n) * poolSize);
        for (int i = 0; i < n; ++i) {
            const cv::Mat& gray = images[samples[i].image].gray;
            for (int p = 0; p < poolSize; ++p)
                intensity[std::size_t(i) * poolSize + p] = static_cast<std::uint8_t>(pixelAt(gray, pointOf(pool[p], anchors[i])));
        }
        auto diff = [&](int i, int a, int b) {
            return int(intensity[std::size_t(i) * poolSize + a]) - int(intensity[std::size_t(i) * poolSize + b]);
        };
        std::uniform_real_distribution<float> uniform(0.f, 1.f);
        for (int k = 0; k < treesPerLandmark; ++k) {
            const int t = l * treesPerLandmark + k;
            std::vector<PoolSplit> tree(splitsPerTree);
            std::vector<std::vector<int>> nodeSamples(2 * splitsPerTree + 1);
            for (int i = 0; i < n; ++i) {
                if (uniform(rng) < o.tree_sample_fraction) nodeSamples[0].push_back(i);
            }
            for (int node = 0; node < splitsPerTree; ++node) {
                auto& here = nodeSamples[node];
                if (here.size() >= 2) {
                    Eigen::Vector2d total = Eigen::Vector2d::Zero();
                    for (int i : here) total += Eigen::Vector2d(targets(i, 2 * l), targets(i, 2 * l + 1));
                    double bestScore = -1.0;
                    for (int c = 0; c < o.split_candidates; ++c) {
                        const int a = static_cast<int>(rng() % poolSize), b = static_cast<int>(rng() % poolSize);
                        if (a == b) continue;
                        const int threshold = diff(here[rng() % here.size()], a, b);
                        Eigen::Vector2d left = Eigen::Vector2d::Zero();
                        int nLeft = 0;
                        for (int i : here) {
                            if (diff(i, a, b) < threshold) {
                                left += Eigen::Vector2d(targets(i, 2 * l), targets(i, 2 * l + 1));
                                ++nLeft;
                            }
                        }
                        const int nRight = static_cast<int>(here.size()) - nLeft;
                        if (nLeft == 0 || nRight == 0) continue;
                        // Variance reduction = |sum_L|^2/n_L + |sum_R|^2/n_R - |sum|^2/n.
                        const double score = left.squaredNorm() / nLeft + (total - left).squaredNorm() / nRight;
                        if (score > bestScore) {
                            bestScore = score;
                            tree[node] = {a, b, threshold};
                        }
                    }
                }
                for (int i : here) {
                    const auto& s = tree[node];
                    nodeSamples[2 * node + (diff(i, s.a, s.b) < s.threshold ? 1 : 2)].push_back(i);
                }
                here.clear();
                here.shrink_to_fit();
            }
            for (int node = 0; node < splitsPerTree; ++node) {
                const auto& s = tree[node];
                stage.splits[std::size_t(t) * splitsPerTree + node] = {pool[s.a], pool[s.b], static_cast<std::int16_t>(s.threshold)};
            }
            for (int i = 0; i < n; ++i) {
                int node = 0;
                while (node < splitsPerTree) node = 2 * node + (diff(i, tree[node].a, tree[node].b) < tree[node].threshold ? 1 : 2);
                leafOf[std::size_t(i) * trees + t] = t * leaves + (node - splitsPerTree);
            }
        }
        report("forests", double(++landmarksDone) / kLandmarks);
    });

    // Global regression: ridge least squares over the binary features, by exact
    // block coordinate descent. Within one tree the leaf columns are disjoint,
    // so each block's normal matrix is diagonal and its minimiser is a
    // per-leaf mean of the residuals, shrunk by the ridge weight.
    std::vector<std::vector<int>> byLeaf(static_cast<std::size_t>(trees) * leaves);
    for (int i = 0; i < n; ++i) {
        for (int t = 0; t < trees; ++t) byLeaf[leafOf[std::size_t(i) * trees + t]].push_back(i);
    }
    RegressionRows weights = RegressionRows::Zero(static_cast<Eigen::Index>(trees) * leaves, 2 * kLandmarks);
    Targets residual = targets;
    constexpr int kColumnBlocks = 8;
    std::atomic<int> blocksDone{0};
    parallelFor(kColumnBlocks, o.threads, [&](int block) {
        const int c0 = block * (2 * kLandmarks) / kColumnBlocks, c1 = (block + 1) * (2 * kLandmarks) / kColumnBlocks;
        Eigen::VectorXf sum(c1 - c0);
        for (int epoch = 0; epoch < o.ridge_epochs; ++epoch) {
            for (std::size_t row = 0; row < byLeaf.size(); ++row) {
                const auto& members = byLeaf[row];
                if (members.empty()) continue;
                auto w = weights.row(static_cast<Eigen::Index>(row)).segment(c0, c1 - c0);
                sum = static_cast<float>(members.size()) * w.transpose();
                for (int i : members) sum += residual.row(i).segment(c0, c1 - c0).transpose();
                const Eigen::VectorXf update = sum / (static_cast<float>(members.size()) + o.ridge) - w.transpose();
                w += update.transpose();
                for (int i : members) residual.row(i).segment(c0, c1 - c0) -= update.transpose();
            }
        }
        report("global regression", double(++blocksDone) / kColumnBlocks);
    });

    // Quantised before the samples move on, so that later stages learn what
    // the run time will actually apply.
    stage.setRegression(weights);
    model.stages.push_back(std::move(stage));
    parallelFor(n, o.threads, [&](int i) { applyStage(model, model.stages.back(), images[samples[i].image].gray, samples[i].shape); });
}

double meanNme(const std::vector<TrainingImage>& images, const std::vector<TrainingSample>& samples) {
    double sum = 0.0;
    for (const auto& s : samples) sum += core::nme68(core::Shape2(s.shape), core::Shape2(images[s.image].truth));
    return samples.empty() ? 0.0 : sum / static_cast<double>(samples.size());
}

}  // namespace facetrack::landmarks
