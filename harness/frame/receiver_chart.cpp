// The measurement receiver's chart (docs/design.md section 3).
#include <caustics/frame/receiver_chart.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace caustics {

ReceiverChart::ReceiverChart(const FrameGeometry& frame, int width, int height)
    : receiver_(&frame.receiver()), width_(width), height_(height) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("ReceiverChart: resolution must be positive");
    const Object& o = *receiver_->object;
    areas_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0.0);
    if (o.shape == ShapeType::Plane) {
        plane_ = true;
        center_ = o.center;
        u_ = o.u;
        v_ = o.v;
        n_ = glm::normalize(glm::cross(u_, v_));
        const double area = glm::length(glm::cross(u_, v_));
        std::fill(areas_.begin(), areas_.end(), area / (static_cast<double>(width) * height));
        total_area_ = area;
        return;
    }
    if (o.shape != ShapeType::HeightField || !receiver_->heightfield)
        throw std::invalid_argument("ReceiverChart: the receiver '" + o.name + "' is neither a plane nor a height field");
    plane_ = false;
    const HeightField& hf = *receiver_->heightfield;
    const glm::dvec2 ext = hf.extent();
    center_ = glm::dvec3(hf.origin + 0.5 * ext, 0.0);
    u_ = glm::dvec3(ext.x, 0.0, 0.0);
    v_ = glm::dvec3(0.0, ext.y, 0.0);
    n_ = glm::dvec3(0.0, 0.0, 1.0);
    // True surface area of each bin: midpoint rule on sqrt(1 + |grad h|^2) with enough sub-samples per
    // bin to resolve the height-field grid (at least 2 x 2, at most 16 x 16).
    const int sub_x = std::clamp((hf.nx - 1 + width - 1) / width * 2, 2, 16);
    const int sub_y = std::clamp((hf.ny - 1 + height - 1) / height * 2, 2, 16);
    const double bw = ext.x / width, bh = ext.y / height;
    const double da = bw * bh / (static_cast<double>(sub_x) * sub_y);
    for (int j = 0; j < height; ++j) {
        for (int i = 0; i < width; ++i) {
            double sum = 0.0;
            for (int b = 0; b < sub_y; ++b) {
                const double y = hf.origin.y + (j + (b + 0.5) / sub_y) * bh;
                for (int a = 0; a < sub_x; ++a) {
                    const double x = hf.origin.x + (i + (a + 0.5) / sub_x) * bw;
                    const glm::dvec2 g = hf.sample_gradient(x, y);
                    sum += std::sqrt(1.0 + glm::dot(g, g));
                }
            }
            areas_[static_cast<std::size_t>(j) * width + i] = sum * da;
            total_area_ += sum * da;
        }
    }
}

glm::dvec3 ReceiverChart::point(double s, double t) const {
    if (plane_) return center_ + (s - 0.5) * u_ + (t - 0.5) * v_;
    const HeightField& hf = *receiver_->heightfield;
    const double x = center_.x + (s - 0.5) * u_.x, y = center_.y + (t - 0.5) * v_.y;
    return {x, y, hf.sample_height(x, y)};
}

glm::dvec3 ReceiverChart::normal(double s, double t) const {
    if (plane_) return n_;
    const double x = center_.x + (s - 0.5) * u_.x, y = center_.y + (t - 0.5) * v_.y;
    return receiver_->heightfield->sample_normal(x, y);
}

bool ReceiverChart::coords(const glm::dvec3& p, double& s, double& t) const {
    if (plane_) {
        // Solve (p - center) projected onto span(u, v) = (s - 1/2) u + (t - 1/2) v; u, v need not be
        // orthogonal, so use the 2 x 2 Gram system.
        const glm::dvec3 d = p - center_;
        const double uu = glm::dot(u_, u_), uv = glm::dot(u_, v_), vv = glm::dot(v_, v_);
        const double du = glm::dot(d, u_), dv = glm::dot(d, v_);
        const double det = uu * vv - uv * uv;
        s = (du * vv - dv * uv) / det + 0.5;
        t = (dv * uu - du * uv) / det + 0.5;
    } else {
        s = (p.x - center_.x) / u_.x + 0.5;
        t = (p.y - center_.y) / v_.y + 0.5;
    }
    return s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0;
}

int ReceiverChart::bin_of(const glm::dvec3& p) const {
    double s, t;
    if (!coords(p, s, t)) return -1;
    const int i = std::min(static_cast<int>(s * width_), width_ - 1);
    const int j = std::min(static_cast<int>(t * height_), height_ - 1);
    return j * width_ + i;
}

}  // namespace caustics
