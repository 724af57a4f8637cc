#include <caustics/view/param_model.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include <caustics/util/errors.hpp>

namespace caustics::view {
namespace {

double parse_number(const std::string& owner, const ParamSpec& spec, const std::string& text) {
    try {
        std::size_t used = 0;
        const double v = std::stod(text, &used);
        if (used == text.size() && std::isfinite(v)) return v;
    } catch (const std::exception&) {
    }
    throw InputError(owner, spec.name, "'" + text + "' is not a number; valid: " + spec.valid_text());
}

// The slider range of a numeric parameter (header comment).
void slider_range(const ParamSpec& spec, double current, ParamWidget& w) {
    const double d = spec.default_value.empty() ? 0.0 : std::stod(spec.default_value);
    const double span = 10.0 * std::max(std::fabs(d), 1.0);
    const bool fin_lo = std::isfinite(spec.min), fin_hi = std::isfinite(spec.max);
    w.declared_unbounded = !fin_lo || !fin_hi;
    double lo = fin_lo ? spec.min : (fin_hi ? std::min(d, spec.max) : d) - span;
    double hi = fin_hi ? spec.max : std::max(d, lo) + span;
    if (spec.type == ParamType::Int) {
        lo = fin_lo ? lo : std::ceil(lo);
        hi = fin_hi ? hi : std::floor(hi);
    }
    // A value set outside the chosen span (never outside the declared range) widens the slider.
    lo = std::min(lo, current);
    hi = std::max(hi, current);
    w.lo = lo;
    w.hi = hi;
    w.logarithmic = lo > 0.0 && hi >= 100.0 * lo;
}

}  // namespace

std::string number_text(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

ParamModel::ParamModel(const MethodInfo& info, const std::map<std::string, std::string>& overrides) : info_(&info) {
    params_ = ParamSet::resolve(info.name, info.params, overrides);
    values_ = params_.values();
    for (const ParamSpec& spec : info.params) {
        ParamWidget w;
        w.name = spec.name;
        w.doc = spec.doc;
        switch (spec.type) {
        case ParamType::Int:
            w.kind = WidgetKind::IntSlider;
            slider_range(spec, static_cast<double>(params_.get_int(spec.name)), w);
            break;
        case ParamType::Float:
            w.kind = WidgetKind::FloatSlider;
            slider_range(spec, params_.get_float(spec.name), w);
            break;
        case ParamType::Enum:
            w.kind = WidgetKind::Combo;
            w.choices = spec.choices;
            break;
        case ParamType::Bool:
            w.kind = WidgetKind::Checkbox;
            break;
        }
        widgets_.push_back(std::move(w));
    }
    refresh();
}

void ParamModel::refresh() {
    for (std::size_t i = 0; i < widgets_.size(); ++i) {
        ParamWidget& w = widgets_[i];
        w.text = params_.values().at(w.name);
        switch (w.kind) {
        case WidgetKind::IntSlider: w.int_value = params_.get_int(w.name); break;
        case WidgetKind::FloatSlider: w.float_value = params_.get_float(w.name); break;
        case WidgetKind::Combo: {
            const auto it = std::find(w.choices.begin(), w.choices.end(), params_.get_enum(w.name));
            w.choice = static_cast<int>(it - w.choices.begin());
            break;
        }
        case WidgetKind::Checkbox: w.bool_value = params_.get_bool(w.name); break;
        }
    }
}

bool ParamModel::assign(std::size_t i, const std::string& text) {
    std::map<std::string, std::string> next = values_;
    next[widgets_.at(i).name] = text;
    // The table has the last word: a value it refuses is never held (the old set stays).
    ParamSet resolved = ParamSet::resolve(info_->name, info_->params, next);
    if (resolved.values() == params_.values()) return false;
    params_ = std::move(resolved);
    values_ = params_.values();
    refresh();
    return true;
}

bool ParamModel::set_int(std::size_t i, long long v) {
    const ParamWidget& w = widgets_.at(i);
    if (w.kind != WidgetKind::IntSlider) throw std::logic_error("set_int on a non-integer widget " + w.name);
    const long long lo = static_cast<long long>(std::ceil(w.lo)), hi = static_cast<long long>(std::floor(w.hi));
    return assign(i, std::to_string(std::clamp(v, lo, hi)));
}

bool ParamModel::set_float(std::size_t i, double v) {
    const ParamWidget& w = widgets_.at(i);
    if (w.kind != WidgetKind::FloatSlider) throw std::logic_error("set_float on a non-float widget " + w.name);
    if (!std::isfinite(v)) return false;
    return assign(i, number_text(std::clamp(v, w.lo, w.hi)));
}

bool ParamModel::set_choice(std::size_t i, int choice) {
    const ParamWidget& w = widgets_.at(i);
    if (w.kind != WidgetKind::Combo) throw std::logic_error("set_choice on a non-enum widget " + w.name);
    if (w.choices.empty()) return false;
    return assign(i, w.choices[static_cast<std::size_t>(std::clamp(choice, 0, static_cast<int>(w.choices.size()) - 1))]);
}

bool ParamModel::set_bool(std::size_t i, bool v) {
    const ParamWidget& w = widgets_.at(i);
    if (w.kind != WidgetKind::Checkbox) throw std::logic_error("set_bool on a non-bool widget " + w.name);
    return assign(i, v ? "true" : "false");
}

bool ParamModel::set_text(const std::string& name, const std::string& text) {
    for (std::size_t i = 0; i < widgets_.size(); ++i) {
        if (widgets_[i].name != name) continue;
        const ParamSpec& spec = info_->params[i];
        switch (widgets_[i].kind) {
        case WidgetKind::IntSlider: return set_int(i, std::llround(parse_number(info_->name, spec, text)));
        case WidgetKind::FloatSlider: return set_float(i, parse_number(info_->name, spec, text));
        case WidgetKind::Combo: return assign(i, text);   // resolve refuses an unknown choice
        case WidgetKind::Checkbox: return assign(i, text);
        }
    }
    throw InputError(info_->name, name, "unknown parameter");
}

std::map<std::string, std::string> ParamModel::overrides() const {
    const ParamSet defaults = ParamSet::resolve(info_->name, info_->params, {});
    std::map<std::string, std::string> out;
    for (const auto& [name, text] : params_.values())
        if (defaults.values().at(name) != text) out[name] = text;
    return out;
}

}  // namespace caustics::view
