#pragma once
// The live-parameter widgets of the viewer, generated from a method's parameter table (MethodInfo::params),
// never written per method. Ints and floats become sliders within the declared range, enums combos,
// bools checkboxes. Every setter clamps to the widget's range and re-resolves the whole ParamSet through
// the table (ParamSet::resolve), so an invalid value cannot be entered: the model always holds a set the
// method accepts.
//
// A slider needs finite ends. Where the table declares an infinite bound, the slider's end is the
// default moved by ten times max(|default|, 1) (for ints, rounded inwards), and never past the finite
// bound: e.g. a float in [0, inf) with default 0.5 slides over [0, 10.5]. A value given with --set
// outside that span widens the slider to include it. A range whose ends are both positive and at least
// a factor 100 apart slides logarithmically.
#include <map>
#include <string>
#include <vector>

#include <caustics/api/method.hpp>
#include <caustics/api/params.hpp>

namespace caustics::view {

enum class WidgetKind { IntSlider, FloatSlider, Combo, Checkbox };

struct ParamWidget {
    std::string name;
    std::string doc;
    WidgetKind kind = WidgetKind::FloatSlider;
    double lo = 0.0, hi = 0.0;        // slider range (finite, inside the declared range)
    bool logarithmic = false;
    bool declared_unbounded = false;  // the table declares an infinite bound (the slider's end is chosen)
    std::vector<std::string> choices; // Combo
    // The current value: its canonical text (ParamSet::values) and typed.
    std::string text;
    long long int_value = 0;
    double float_value = 0.0;
    int choice = 0;
    bool bool_value = false;
};

class ParamModel {
public:
    // Throws InputError (naming the key) for an override the table refuses.
    ParamModel(const MethodInfo& info, const std::map<std::string, std::string>& overrides = {});

    const MethodInfo& info() const { return *info_; }
    const std::vector<ParamWidget>& widgets() const { return widgets_; }
    const ParamSet& params() const { return params_; }
    // The parameters that differ from their defaults (canonical text): what --set needs to say.
    std::map<std::string, std::string> overrides() const;

    // Setters clamp into the widget's range (ints rounded) and return whether the value changed.
    bool set_int(std::size_t i, long long v);
    bool set_float(std::size_t i, double v);
    bool set_choice(std::size_t i, int choice);
    bool set_bool(std::size_t i, bool v);
    // Any widget from text ("64", "0.5", "newton", "true"): clamped like the typed setters; InputError for
    // text that is not a value of the widget's type or an unknown name.
    bool set_text(const std::string& name, const std::string& text);

private:
    bool assign(std::size_t i, const std::string& text);
    void refresh();
    const MethodInfo* info_;
    std::vector<ParamWidget> widgets_;
    std::map<std::string, std::string> values_;   // name -> canonical text
    ParamSet params_;
};

// The text of a double that reads back to the same double (shortest round trip).
std::string number_text(double v);

}  // namespace caustics::view
