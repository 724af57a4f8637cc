// The viewer's window-free model (harness/view): the parameter widgets generated for every registered
// method's table stay inside the declared ranges and cannot hold an invalid value; the colour maps; the
// panes and the hover readout of a session; the record actions (a render command line and a sweep-spec
// fragment that the sweep reader accepts).
#include <cmath>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>

#include <caustics/api/registry.hpp>
#include <caustics/sweep/sweep_spec.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/view/colormap.hpp>
#include <caustics/view/param_model.hpp>
#include <caustics/view/record.hpp>
#include <caustics/view/session.hpp>
#include <caustics/view/views.hpp>

#include "test_support.hpp"

namespace caustics {
namespace {

using view::ParamModel;
using view::WidgetKind;

// The value a widget holds, as a number (ints and floats).
double numeric(const view::ParamWidget& w) {
    return w.kind == WidgetKind::IntSlider ? static_cast<double>(w.int_value) : w.float_value;
}

TEST(ViewParamModel, WidgetsOfEveryRegisteredMethodRespectTheirRanges) {
    const auto methods = registered_methods();
    ASSERT_FALSE(methods.empty());
    for (const MethodInfo* info : methods) {
        SCOPED_TRACE(info->name);
        ParamModel pm(*info);
        ASSERT_EQ(pm.widgets().size(), info->params.size());
        for (std::size_t i = 0; i < info->params.size(); ++i) {
            const ParamSpec& spec = info->params[i];
            SCOPED_TRACE(spec.name);
            const view::ParamWidget& w = pm.widgets()[i];
            EXPECT_EQ(w.name, spec.name);
            switch (spec.type) {
            case ParamType::Int:
            case ParamType::Float: {
                EXPECT_EQ(w.kind, spec.type == ParamType::Int ? WidgetKind::IntSlider : WidgetKind::FloatSlider);
                ASSERT_TRUE(std::isfinite(w.lo) && std::isfinite(w.hi));
                EXPECT_GE(w.lo, spec.min);
                EXPECT_LE(w.hi, spec.max);
                EXPECT_LE(w.lo, w.hi);
                if (w.logarithmic) {
                    EXPECT_GT(w.lo, 0.0);
                }
                EXPECT_GE(numeric(w), w.lo);
                EXPECT_LE(numeric(w), w.hi);
                EXPECT_EQ(w.declared_unbounded, !std::isfinite(spec.min) || !std::isfinite(spec.max));
                // Far below, far above, the middle: always clamped into [lo, hi], always a valid set.
                for (double v : {w.lo - 1e9, w.hi + 1e9, 0.5 * (w.lo + w.hi), w.lo, w.hi}) {
                    if (w.kind == WidgetKind::IntSlider) pm.set_int(i, std::llround(v));
                    else pm.set_float(i, v);
                    const view::ParamWidget& now = pm.widgets()[i];
                    EXPECT_GE(numeric(now), std::max(w.lo, spec.min));
                    EXPECT_LE(numeric(now), std::min(w.hi, spec.max));
                    EXPECT_NO_THROW(ParamSet::resolve(info->name, info->params, pm.params().values()));
                }
                if (w.kind == WidgetKind::FloatSlider) {
                    EXPECT_FALSE(pm.set_float(i, std::numeric_limits<double>::quiet_NaN()));
                }
                EXPECT_THROW(pm.set_text(spec.name, "not-a-number"), InputError);
                break;
            }
            case ParamType::Enum:
                EXPECT_EQ(w.kind, WidgetKind::Combo);
                EXPECT_EQ(w.choices, spec.choices);
                pm.set_choice(i, -5);
                EXPECT_EQ(pm.widgets()[i].choice, 0);
                pm.set_choice(i, static_cast<int>(spec.choices.size()) + 3);
                EXPECT_EQ(pm.widgets()[i].choice, static_cast<int>(spec.choices.size()) - 1);
                EXPECT_EQ(pm.params().get_enum(spec.name), spec.choices.back());
                EXPECT_THROW(pm.set_text(spec.name, "no-such-choice"), InputError);
                EXPECT_EQ(pm.params().get_enum(spec.name), spec.choices.back());   // the refused value is not held
                break;
            case ParamType::Bool:
                EXPECT_EQ(w.kind, WidgetKind::Checkbox);
                pm.set_bool(i, !w.bool_value);
                EXPECT_EQ(pm.params().get_bool(spec.name), pm.widgets()[i].bool_value);
                break;
            }
        }
    }
}

MethodInfo synthetic_table() {
    MethodInfo info;
    info.name = "synthetic";
    const double inf = std::numeric_limits<double>::infinity();
    info.params = {
        {"grid", ParamType::Int, "64", 1, 4096, {}, "grid"},
        {"iterations", ParamType::Int, "0", -inf, inf, {}, "unbounded both ways"},
        {"radius", ParamType::Float, "0.5", 0.0, inf, {}, "half-open"},
        {"count", ParamType::Float, "1e6", 1.0, inf, {}, "large default"},
        {"below", ParamType::Float, "-2", -inf, 3.0, {}, "bounded above"},
    };
    return info;
}

TEST(ViewParamModel, InfiniteBoundsGetTheDocumentedSliderSpan) {
    const MethodInfo info = synthetic_table();
    const ParamModel pm(info);
    const auto& w = pm.widgets();
    EXPECT_EQ(w[0].lo, 1.0);
    EXPECT_EQ(w[0].hi, 4096.0);
    EXPECT_TRUE(w[0].logarithmic);
    EXPECT_EQ(w[1].lo, -10.0);          // default 0 -/+ 10 max(|0|, 1)
    EXPECT_EQ(w[1].hi, 10.0);
    EXPECT_EQ(w[2].lo, 0.0);
    EXPECT_DOUBLE_EQ(w[2].hi, 10.5);    // 0.5 + 10 max(0.5, 1)
    EXPECT_FALSE(w[2].logarithmic);     // lo = 0
    EXPECT_DOUBLE_EQ(w[3].hi, 1.1e7);   // 1e6 + 10e6
    EXPECT_TRUE(w[3].logarithmic);
    EXPECT_DOUBLE_EQ(w[4].lo, -22.0);   // min(-2, 3) - 20
    EXPECT_EQ(w[4].hi, 3.0);
    // A value given with --set beyond the chosen span widens the slider, within the declared range.
    const ParamModel wide(info, {{"radius", "100"}});
    EXPECT_EQ(wide.widgets()[2].hi, 100.0);
    EXPECT_EQ(wide.overrides(), (std::map<std::string, std::string>{{"radius", "100"}}));
    EXPECT_THROW(ParamModel(info, {{"radius", "-1"}}), InputError);
}

TEST(ViewColorMap, MappingsAndTables) {
    using namespace view;
    EXPECT_EQ(colormap_rgba(ColorMap::Diverging, 0.5), (Rgba{255, 255, 255, 255}));   // zero difference is white
    EXPECT_EQ(colormap_rgba(ColorMap::Grey, 1.0), (Rgba{255, 255, 255, 255}));
    EXPECT_EQ(colormap_rgba(ColorMap::Grey, 0.0), (Rgba{0, 0, 0, 255}));
    Mapping lin{Exposure::Linear, ColorMap::Grey, 2.0};
    EXPECT_DOUBLE_EQ(lin.normalise(1.0), 0.5);
    EXPECT_DOUBLE_EQ(lin.normalise(5.0), 1.0);
    EXPECT_DOUBLE_EQ(lin.normalise(-1.0), 0.0);
    Mapping log{Exposure::Log, ColorMap::Grey, 10.0, 2.0};
    EXPECT_DOUBLE_EQ(log.normalise(10.0), 1.0);
    EXPECT_DOUBLE_EQ(log.normalise(1.0), 0.5);
    EXPECT_DOUBLE_EQ(log.normalise(0.1), 0.0);
    Mapping sym{Exposure::Linear, ColorMap::Diverging, 4.0, 3.0, true};
    EXPECT_DOUBLE_EQ(sym.normalise(-4.0), 0.0);
    EXPECT_DOUBLE_EQ(sym.normalise(0.0), 0.5);
    EXPECT_DOUBLE_EQ(sym.normalise(2.0), 0.75);
    Image im(3, 1);
    im.pixels = {1.0f, std::numeric_limits<float>::quiet_NaN(), 2.0f};
    const std::vector<std::uint8_t> mask = {1, 1, 0};
    const auto rgba = map_to_rgba8(im, lin, &mask);
    EXPECT_EQ(rgba[0], 128);   // round(255 * 0.5)
    EXPECT_EQ((Rgba{rgba[4], rgba[5], rgba[6], rgba[7]}), invalid_rgba());
    EXPECT_EQ(rgba[8], 40);    // masked out
    Image ramp(100, 1);
    for (int i = 0; i < 100; ++i) ramp.pixels[i] = static_cast<float>(i + 1);
    EXPECT_NEAR(robust_scale(ramp, 0.5), 50.5, 0.6);
    EXPECT_EQ(robust_scale(Image(4, 4)), 1.0);   // nothing positive: 1
}

TEST(ViewSession, PanesReadoutAndRecordOnSine) {
    view::SessionOptions o;
    o.scene = "sine";
    o.reference = false;   // the receiver's truth is the sine's closed form
    view::Session s(o);
    ASSERT_FALSE(s.method_name().empty());
    for (const view::MethodChoice& c : s.methods())
        if (c.name == s.method_name()) {
            EXPECT_TRUE(c.supported);
        }
    s.render();
    ASSERT_TRUE(s.rendered());
    EXPECT_GT(s.timing().median_frame_ms, 0.0);
    ASSERT_TRUE(s.errors().view("receiver") != nullptr);
    EXPECT_TRUE(s.errors().view("receiver")->net.valid);
    EXPECT_EQ(s.errors().truth_kind.rfind("analytic", 0), 0u);

    const view::DisplaySettings d;
    for (view::ViewKind k : {view::ViewKind::MethodReceiver, view::ViewKind::ReferenceReceiver, view::ViewKind::DifferenceReceiver}) {
        const view::Pane p = view::make_pane(s, k, d);
        ASSERT_TRUE(p.available) << view::to_string(k) << ": " << p.missing;
        EXPECT_EQ(p.width, s.scene().receiver.width);
        EXPECT_EQ(p.rgba.size(), static_cast<std::size_t>(p.width) * p.height * 4);
    }
    EXPECT_FALSE(view::make_pane(s, view::ViewKind::ReferenceCamera, d).available);   // no reference asked for
    // Method and reference share one mapping; the difference's is symmetric.
    const view::Pane m = view::make_pane(s, view::ViewKind::MethodReceiver, d);
    const view::Pane r = view::make_pane(s, view::ViewKind::ReferenceReceiver, d);
    EXPECT_EQ(m.mapping.scale, r.mapping.scale);
    EXPECT_TRUE(view::make_pane(s, view::ViewKind::DifferenceReceiver, d).mapping.signed_range);

    const int x = s.scene().receiver.width / 3, y = s.scene().receiver.height / 2;
    const view::Readout ro = view::readout(s, view::Space::Receiver, x, y);
    ASSERT_TRUE(ro.valid);
    EXPECT_EQ(ro.method, s.output().receiver.at(x, y));
    ASSERT_TRUE(ro.truth.has_value());
    EXPECT_EQ(*ro.truth, s.receiver_truth()->at(x, y));
    EXPECT_FALSE(ro.z.has_value());   // a closed form has no standard error
    EXPECT_FALSE(view::readout(s, view::Space::Receiver, -1, 0).valid);

    // Record: the grid at its slider's low end appears as --set, and the sweep reader takes the fragment.
    std::size_t grid = 0;
    while (s.params().widgets()[grid].name != "grid") ++grid;
    const auto& gw = s.params().widgets()[grid];
    const long long other = gw.int_value == static_cast<long long>(gw.lo) ? static_cast<long long>(gw.hi) : static_cast<long long>(gw.lo);
    if (s.params().set_int(grid, other)) s.parameters_changed();
    const std::string cmd = view::render_command_line(s);
    EXPECT_NE(cmd.find("caustics render sine --method " + s.method_name()), std::string::npos) << cmd;
    EXPECT_NE(cmd.find("--set grid=" + std::to_string(other)), std::string::npos) << cmd;
    EXPECT_NE(cmd.find("--frame 0"), std::string::npos) << cmd;
    test_support::ScopedTempDir dir("view_record");
    std::filesystem::create_directories(dir.path());
    const auto spec_path = dir.path() / "fragment.json";
    std::ofstream(spec_path) << view::sweep_fragment(s).dump(2);
    const SweepSpec spec = load_sweep_spec(spec_path.string());
    ASSERT_EQ(spec.methods.size(), 1u);
    EXPECT_EQ(spec.methods[0].method, s.method_name());
    bool found = false;
    for (const SweepAxis& a : spec.methods[0].axes)
        if (a.name == "grid") {
            found = true;
            EXPECT_EQ(a.values, std::vector<std::string>{std::to_string(other)});
        }
    EXPECT_TRUE(found);
}

}  // namespace
}  // namespace caustics

namespace caustics {
namespace {

// Scrubbing: a frame change abandons the old frame's reference without waiting for it, and the new
// frame's reference reaches its photons; while playing (no reference) none is started until asked.
TEST(ViewSession, FrameChangesAbandonTheOldReferenceAndStartTheNewOne) {
    view::SessionOptions o;
    o.scene = "pool";
    o.frame = 10;
    o.progressive.reference.photons = 16'000;
    o.progressive.reference.progress = false;
    o.progressive.first_round = 2'000;
    o.progressive.cache_dir = "";   // computed here, never cached
    view::Session s(o);
    EXPECT_EQ(s.frame_count(), 120);
    s.set_frame(11);
    s.set_frame(12, false);   // playing: no reference
    EXPECT_EQ(s.progressive(), nullptr);
    s.ensure_reference();
    ASSERT_NE(s.progressive(), nullptr);
    s.set_frame(500);         // clamped to the last frame
    EXPECT_EQ(s.frame(), 119);
    s.wait_for_reference();
    const auto r = s.reference();
    ASSERT_TRUE(r);
    EXPECT_EQ(r->photons, s.reference_status().target);
    EXPECT_GT(s.reference_status().rounds, 1);
    s.render();
    ASSERT_TRUE(s.errors().view("receiver") != nullptr);
    EXPECT_EQ(s.errors().photons, r->photons);
}

}  // namespace
}  // namespace caustics
