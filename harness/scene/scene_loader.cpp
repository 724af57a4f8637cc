// load_scene: the JSON scene format of docs/design.md section 8 (the format is fixed in
// scenes/README.md). Every field is validated; any problem is an InputError naming the file, the
// key path ("objects[2].material.ior") and what would be valid.
//
// Magnitudes are bounded by what the computation can represent (limits.hpp): every coordinate the
// geometry can reach within |x| <= kMaxCoordinate (single-precision geometry in Embree), lengths that
// divide at least kMinLength, absorption and scattering at most kMaxCoefficient, light powers within
// [kMinPower, kMaxPower], and the memory the resolutions imply under the ceiling (check_scene_memory).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>

#include <caustics/util/errors.hpp>
#include <caustics/scene/gltf_mesh.hpp>
#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/util/json_reader.hpp>
#include <caustics/scene/limits.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics {

namespace {

namespace fs = std::filesystem;

constexpr int kMaxImageSize = 16384;    // camera and receiver maps
constexpr int kMaxGridCells = 8192;     // height-field cells per axis
constexpr std::int64_t kMaxFrames = 1000000;
constexpr double kMaxNoiseSamples = 67108864.0;  // 2^26: 1024 x 1024 cells x 64 time samples

// ---- magnitudes (limits.hpp)

std::string coordinate_bound() {
    return "|x|, |y|, |z| <= " + format_limit(kMaxCoordinate) + " m (geometry is single precision in Embree)";
}

std::string vec_text(const glm::dvec3& p) {
    char text[96];
    std::snprintf(text, sizeof text, "(%g, %g, %g)", p.x, p.y, p.z);
    return text;
}

bool within_bound(const glm::dvec3& p) {
    return std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate && std::abs(p.z) <= kMaxCoordinate;
}

// `p` (what the geometry at key `n` reaches, described by `what`) must lie within the coordinate bound.
// An empty `what`: the point at key `n` itself.
void require_within(const JsonNode& n, const glm::dvec3& p, const std::string& what) {
    if (within_bound(p)) return;
    n.fail((what.empty() ? vec_text(p) + " is" : what + " " + vec_text(p) + ",") +
           " beyond the representable range; valid: " + coordinate_bound());
}

glm::dvec3 bounded_vec3(const JsonNode& n) {
    const glm::dvec3 p = n.as_vec3();
    require_within(n, p, "");
    return p;
}

// Every corner of the box lo..hi.
void require_box_within(const JsonNode& n, const glm::dvec3& lo, const glm::dvec3& hi, const std::string& what) {
    require_within(n, lo, what);
    require_within(n, hi, what);
}

// A length that divides: at least kMinLength (and finite).
void require_length(const JsonNode& n, double length, const std::string& what) {
    if (!(length >= kMinLength))
        n.fail(what + " " + format_limit(length) + " m is too small to represent; valid: >= " + format_limit(kMinLength) +
               " m (float positions collapse below it)");
}

// An absorption or scattering coefficient [1/m].
double coefficient(const JsonNode& n) {
    const double x = n.as_nonnegative();
    if (x > kMaxCoefficient)
        n.fail("got " + format_limit(x) + " /m: no light would survive (at " + format_limit(kMaxCoefficient) +
               " /m it falls below the reference's resolution, e^-21, within 2.1 mm); valid: [0, " +
               format_limit(kMaxCoefficient) + "] /m");
    return x;
}

// Irradiance [W/m^2] or intensity [W/sr].
double light_power(const JsonNode& n, const char* unit) {
    const double x = n.as_positive();
    if (x < kMinPower || x > kMaxPower)
        n.fail("got " + format_limit(x) + " " + unit + "; valid: [" + format_limit(kMinPower) + ", " +
               format_limit(kMaxPower) + "] " + unit + " (irradiance images are float32)");
    return x;
}

// A height-field amplitude: |base_height| + |amplitude| within the coordinate bound.
double amplitude_within(const JsonNode& n, double amplitude, double base_height) {
    if (!(std::abs(base_height) + std::abs(amplitude) <= kMaxCoordinate))
        n.fail("the surface would reach z = " + format_limit(base_height) + " + " + format_limit(amplitude) +
               " m; valid: |base_height| + |amplitude| <= " + format_limit(kMaxCoordinate) +
               " m (geometry is single precision in Embree)");
    return amplitude;
}

// Scene-relative asset path, resolved against the scene file's folder.
std::string resolve_asset(const std::string& scene_path, const std::string& file) {
    fs::path p(file);
    if (p.is_relative()) p = fs::path(scene_path).parent_path() / p;
    return p.lexically_normal().string();
}

// Fails unless `path` is a readable regular file.
void require_readable(const JsonNode& node, const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) node.fail("the file '" + path + "' does not exist (paths are relative to the scene file's folder)");
    if (!fs::is_regular_file(path, ec)) node.fail("'" + path + "' is not a regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in || in.peek() == std::ifstream::traits_type::eof()) node.fail("the file '" + path + "' cannot be read or is empty");
}

Light parse_light(const JsonNode& n) {
    n.expect_object();
    Light l;
    const std::string type = n.at("type").as_enum({"directional", "point"});
    if (type == "directional") {
        n.check_keys({"type", "direction", "irradiance"});
        l.type = LightType::Directional;
        l.direction = glm::normalize(n.at("direction").as_nonzero_vec3());
        if (n.has("irradiance")) l.irradiance = light_power(n.at("irradiance"), "W/m^2");
    } else {
        n.check_keys({"type", "position", "intensity"});
        l.type = LightType::Point;
        l.position = bounded_vec3(n.at("position"));
        if (n.has("intensity")) l.intensity = light_power(n.at("intensity"), "W/sr");
    }
    return l;
}

Camera parse_camera(const JsonNode& n) {
    n.check_keys({"position", "look_at", "up", "fov_y", "width", "height"});
    Camera c;
    if (n.has("position")) c.position = bounded_vec3(n.at("position"));
    if (n.has("look_at")) c.look_at = bounded_vec3(n.at("look_at"));
    if (n.has("up")) c.up = n.at("up").as_nonzero_vec3();
    if (n.has("fov_y")) c.fov_y_deg = n.at("fov_y").as_number_in(0.0, 180.0, true, true);
    if (n.has("width")) c.width = static_cast<int>(n.at("width").as_integer_in(1, kMaxImageSize));
    if (n.has("height")) c.height = static_cast<int>(n.at("height").as_integer_in(1, kMaxImageSize));
    const glm::dvec3 forward = c.look_at - c.position;
    if (!(glm::length(forward) > 0.0)) n.fail("'position' and 'look_at' must differ");
    if (!(glm::length(glm::cross(glm::normalize(forward), glm::normalize(c.up))) > 1e-9))
        throw InputError(n.file(), n.member_path("up"), "must not be parallel to the viewing direction look_at - position");
    return c;
}

Material parse_material(const JsonNode& n) {
    n.expect_object();
    Material m;
    const std::string type = n.at("type").as_enum({"dielectric", "mirror", "diffuse"});
    if (type == "dielectric") {
        n.check_keys({"type", "ior", "dispersion", "absorption", "medium"});
        m.type = MaterialType::Dielectric;
        m.ior = n.at("ior").as_positive();
        if (n.has("dispersion")) m.dispersion = n.at("dispersion").as_nonnegative();
        if (n.has("absorption")) m.absorption = coefficient(n.at("absorption"));
        if (n.has("medium")) {
            // The medium inside the object; `absorption` on the material is its absorption alone, so
            // the two may not both say it.
            const JsonNode md = n.at("medium");
            md.check_keys({"absorption", "scattering", "anisotropy"});
            if (md.has("absorption")) {
                if (n.has("absorption"))
                    md.at("absorption").fail("repeats the material's `absorption`; valid: give it in one place");
                m.absorption = coefficient(md.at("absorption"));
            }
            if (md.has("scattering")) m.scattering = coefficient(md.at("scattering"));
            if (md.has("anisotropy")) m.anisotropy = md.at("anisotropy").as_number_in(-1.0, 1.0, true, true);
        }
    } else if (type == "mirror") {
        n.check_keys({"type"});
        m.type = MaterialType::Mirror;
    } else {
        n.check_keys({"type", "albedo"});
        m.type = MaterialType::Diffuse;
        if (n.has("albedo")) {
            const JsonNode a = n.at("albedo");
            m.albedo = a.as_vec3();
            for (int k = 0; k < 3; ++k)
                if (m.albedo[k] < 0.0 || m.albedo[k] > 1.0) a.fail("must be 3 numbers in [0, 1]");
        }
    }
    return m;
}

glm::dmat4 parse_transform(const JsonNode& n) {
    n.check_keys({"translate", "rotate_deg", "scale"});
    glm::dvec3 translate(0.0), rotate(0.0), scale(1.0);
    if (n.has("translate")) translate = n.at("translate").as_vec3();
    if (n.has("rotate_deg")) rotate = n.at("rotate_deg").as_vec3();
    if (n.has("scale")) {
        const JsonNode s = n.at("scale");
        if (s.json().is_number()) scale = glm::dvec3(s.as_number());
        else if (s.json().is_array()) scale = s.as_vec3();
        else s.fail("must be a non-zero number or an array of 3 non-zero numbers");
        if (scale.x == 0.0 || scale.y == 0.0 || scale.z == 0.0) s.fail("must be a non-zero number or an array of 3 non-zero numbers");
    }
    // Object to world: scale, then rotate about x, then y, then z, then translate.
    glm::dmat4 m = glm::translate(glm::dmat4(1.0), translate);
    m = glm::rotate(m, glm::radians(rotate.z), glm::dvec3(0, 0, 1));
    m = glm::rotate(m, glm::radians(rotate.y), glm::dvec3(0, 1, 0));
    m = glm::rotate(m, glm::radians(rotate.x), glm::dvec3(1, 0, 0));
    return glm::scale(m, scale);
}

// World-space mesh: positions by m, normals by the inverse transpose; winding kept outward when m mirrors.
void transform_mesh(TriangleMesh& mesh, const glm::dmat4& m) {
    const glm::dmat3 nm = glm::transpose(glm::inverse(glm::dmat3(m)));
    for (glm::vec3& p : mesh.positions) p = glm::vec3(m * glm::dvec4(glm::dvec3(p), 1.0));
    for (glm::vec3& n : mesh.normals) {
        const glm::dvec3 t = nm * glm::dvec3(n);
        const double len = glm::length(t);
        n = len > 0.0 ? glm::vec3(t / len) : glm::vec3(0.0f, 0.0f, 1.0f);
    }
    if (glm::determinant(glm::dmat3(m)) < 0.0)
        for (glm::uvec3& t : mesh.triangles) std::swap(t.y, t.z);
}

void parse_generator(const JsonNode& n, const std::string& scene_path, HeightFieldDesc& d, std::vector<std::string>& assets) {
    n.expect_object();
    const std::string type = n.at("type").as_enum({"flat", "sine", "gaussian", "noise", "waves", "image"});
    if (type == "flat") {
        n.check_keys({"type"});
        d.generator = HeightGenerator::Flat;
    } else if (type == "sine") {
        n.check_keys({"type", "amplitude", "wavelength", "direction", "phase", "speed"});
        d.generator = HeightGenerator::Sine;
        d.amplitude = amplitude_within(n.at("amplitude"), n.at("amplitude").as_number(), d.base_height);
        d.wavelength = n.at("wavelength").as_positive();
        require_length(n.at("wavelength"), d.wavelength, "a wavelength of");
        if (n.has("direction")) d.direction = glm::normalize(n.at("direction").as_nonzero_vec2());
        if (n.has("phase")) d.phase = n.at("phase").as_number();
        if (n.has("speed")) d.speed = n.at("speed").as_number();
    } else if (type == "gaussian") {
        n.check_keys({"type", "amplitude", "sigma", "center"});
        d.generator = HeightGenerator::Gaussian;
        d.amplitude = amplitude_within(n.at("amplitude"), n.at("amplitude").as_number(), d.base_height);
        d.sigma = n.at("sigma").as_positive();
        require_length(n.at("sigma"), d.sigma, "a width of");
        if (n.has("center")) {
            d.gauss_center = n.at("center").as_vec2();
            require_within(n.at("center"), glm::dvec3(d.gauss_center, 0.0), "");
        }
    } else if (type == "noise") {
        n.check_keys({"type", "amplitude", "spectral_exponent", "min_wavelength", "max_wavelength", "period",
                      "time_samples", "seed"});
        d.generator = HeightGenerator::Noise;
        d.amplitude = amplitude_within(n.at("amplitude"), n.at("amplitude").as_nonnegative(), d.base_height);
        if (n.has("spectral_exponent")) d.spectral_exponent = n.at("spectral_exponent").as_number_in(0.0, 20.0);
        if (n.has("min_wavelength")) d.min_wavelength = n.at("min_wavelength").as_nonnegative();
        if (n.has("max_wavelength")) d.max_wavelength = n.at("max_wavelength").as_nonnegative();
        if (d.min_wavelength > 0.0 && d.max_wavelength > 0.0 && !(d.min_wavelength < d.max_wavelength))
            n.at("max_wavelength").fail("must be greater than min_wavelength (or 0 for the tile size)");
        if (n.has("period")) d.period = n.at("period").as_positive();
        if (n.has("time_samples")) d.time_samples = static_cast<int>(n.at("time_samples").as_integer_in(1, 1024));
        if (n.has("seed")) d.seed = n.at("seed").as_seed();
        // The synthesised volume (cells x cells x time samples, three float arrays) must fit in memory.
        const double samples = static_cast<double>(d.resolution.x) * d.resolution.y * d.time_samples;
        if (samples > kMaxNoiseSamples)
            throw InputError(n.file(), n.member_path("time_samples"),
                             "the noise volume resolution.x * resolution.y * time_samples = " +
                                 std::to_string(static_cast<long long>(samples)) + " exceeds " +
                                 std::to_string(static_cast<long long>(kMaxNoiseSamples)) +
                                 "; lower time_samples or the height-field resolution");
    } else if (type == "waves") {
        n.check_keys({"type", "amplitude", "drops", "drop_radius", "wave_speed", "damping", "seed"});
        d.generator = HeightGenerator::Waves;
        d.amplitude = amplitude_within(n.at("amplitude"), n.at("amplitude").as_number(), d.base_height);
        if (n.has("drops")) d.drops = static_cast<int>(n.at("drops").as_integer_in(0, 100000));
        if (n.has("drop_radius")) {
            d.drop_radius = n.at("drop_radius").as_positive();
            require_length(n.at("drop_radius"), d.drop_radius, "a drop radius of");
        }
        if (n.has("wave_speed")) d.wave_speed = n.at("wave_speed").as_number_in(0.0, 1e3, true);
        if (n.has("damping")) d.damping = n.at("damping").as_number_in(0.0, 1e6);
        if (n.has("seed")) d.seed = n.at("seed").as_seed();
    } else {
        n.check_keys({"type", "file", "amplitude"});
        d.generator = HeightGenerator::Image;
        const JsonNode f = n.at("file");
        d.image_path = resolve_asset(scene_path, f.as_string());
        require_readable(f, d.image_path);
        // Header first (its size is checked against the memory ceiling before any pixel is allocated),
        // then the whole image once, so that a truncated or corrupt file is refused here.
        HeightMapInfo info;
        try {
            info = read_height_map_info(d.image_path);
        } catch (const std::exception& e) {
            f.fail(e.what());
        }
        check_allocation(f.file(), f.path(), info.decode_bytes(),
                         "decoding the height map '" + d.image_path + "' (" + std::to_string(info.width) + " x " +
                             std::to_string(info.height) + " pixels, " + std::to_string(info.channels) + " channel(s))");
        try {
            (void)read_height_map(d.image_path, info);
        } catch (const std::exception& e) {
            f.fail(e.what());
        }
        assets.push_back(d.image_path);
        d.amplitude = n.has("amplitude") ? n.at("amplitude").as_number() : 1.0;
        if (n.has("amplitude")) amplitude_within(n.at("amplitude"), d.amplitude, d.base_height);
        else amplitude_within(n, d.amplitude, d.base_height);
    }
}

Object parse_object(const JsonNode& n, const std::string& scene_path, std::vector<std::string>& assets) {
    n.expect_object();
    Object o;
    const JsonNode name = n.at("name");
    o.name = name.as_string();
    if (o.name.empty()) name.fail("must be a non-empty string");
    const std::string shape = n.at("shape").as_enum({"plane", "box", "sphere", "mesh", "heightfield"});
    if (shape == "plane") {
        n.check_keys({"name", "shape", "center", "u", "v", "material"});
        o.shape = ShapeType::Plane;
        o.center = bounded_vec3(n.at("center"));
        // Edges within the coordinate bound first (a length of 1e300 would overflow to infinity).
        for (const char* edge : {"u", "v"}) {
            const glm::dvec3 e = n.at(edge).as_vec3();
            require_within(n.at(edge), 0.5 * e, std::string("the half edge ") + edge + "/2 =");
        }
        o.u = n.at("u").as_nonzero_vec3();
        o.v = n.at("v").as_nonzero_vec3();
        require_length(n.at("u"), glm::length(o.u), "an edge of");
        require_length(n.at("v"), glm::length(o.v), "an edge of");
        if (!(glm::length(glm::cross(o.u, o.v)) > 1e-12 * glm::length(o.u) * glm::length(o.v)))
            n.at("v").fail("must not be parallel to 'u' (the plane would have no area)");
        // The corners center +- u/2 +- v/2.
        const glm::dvec3 half = 0.5 * (glm::abs(o.u) + glm::abs(o.v));
        require_box_within(n.at(glm::length(o.u) >= glm::length(o.v) ? "u" : "v"), o.center - half, o.center + half,
                           "the plane (center +- u/2 +- v/2) reaches");
    } else if (shape == "box") {
        n.check_keys({"name", "shape", "center", "size", "material"});
        o.shape = ShapeType::Box;
        o.center = bounded_vec3(n.at("center"));
        const JsonNode size = n.at("size");
        o.size = size.as_vec3();
        if (!(o.size.x > 0.0 && o.size.y > 0.0 && o.size.z > 0.0)) size.fail("must be 3 finite numbers > 0");
        require_length(size, std::min({o.size.x, o.size.y, o.size.z}), "a side of");
        require_box_within(size, o.center - 0.5 * o.size, o.center + 0.5 * o.size, "the box (center +- size/2) reaches");
    } else if (shape == "sphere") {
        n.check_keys({"name", "shape", "center", "radius", "material"});
        o.shape = ShapeType::Sphere;
        o.center = bounded_vec3(n.at("center"));
        const JsonNode radius = n.at("radius");
        o.radius = radius.as_positive();
        require_length(radius, o.radius, "a radius of");
        require_box_within(radius, o.center - glm::dvec3(o.radius), o.center + glm::dvec3(o.radius),
                           "the sphere (center +- radius) reaches");
    } else if (shape == "mesh") {
        n.check_keys({"name", "shape", "file", "transform", "material"});
        o.shape = ShapeType::Mesh;
        const JsonNode f = n.at("file");
        o.mesh_path = resolve_asset(scene_path, f.as_string());
        require_readable(f, o.mesh_path);
        if (n.has("transform")) o.transform = parse_transform(n.at("transform"));
        std::vector<std::string> dependencies;
        try {
            o.mesh = load_gltf_mesh(o.mesh_path, &dependencies);
        } catch (const MeshDataError& e) {
            f.fail(e.what());
        } catch (const std::exception& e) {
            f.fail(std::string("cannot load the mesh (a glTF 2.0 .gltf or .glb file is expected): ") + e.what());
        }
        if (o.mesh.empty()) f.fail("the mesh file '" + o.mesh_path + "' contains no triangles");
        transform_mesh(o.mesh, o.transform);
        // After the transform: every vertex within the coordinate bound, every normal finite.
        const JsonNode where = n.has("transform") ? n.at("transform") : f;
        for (const glm::vec3& p : o.mesh.positions)
            require_within(where, glm::dvec3(p), "the mesh '" + o.mesh_path + "' reaches the vertex");
        for (const glm::vec3& nv : o.mesh.normals)
            if (!(std::isfinite(nv.x) && std::isfinite(nv.y) && std::isfinite(nv.z)))
                where.fail("the mesh '" + o.mesh_path + "' has a normal " + vec_text(glm::dvec3(nv)) +
                           " after the transform; valid: a transform whose scale keeps the normals finite");
        assets.push_back(o.mesh_path);
        assets.insert(assets.end(), dependencies.begin(), dependencies.end());
    } else {
        n.check_keys({"name", "shape", "center", "size", "resolution", "base_height", "material", "generator"});
        o.shape = ShapeType::HeightField;
        HeightFieldDesc& d = o.heightfield;
        d.center = n.at("center").as_vec2();
        require_within(n.at("center"), glm::dvec3(d.center, 0.0), "");
        const JsonNode size = n.at("size");
        d.size = size.as_vec2();
        if (!(d.size.x > 0.0 && d.size.y > 0.0)) size.fail("must be 2 finite numbers > 0");
        require_length(size, std::min(d.size.x, d.size.y), "a side of");
        require_box_within(size, glm::dvec3(d.center - 0.5 * d.size, 0.0), glm::dvec3(d.center + 0.5 * d.size, 0.0),
                           "the height field (center +- size/2) reaches");
        d.resolution = n.at("resolution").as_ivec2_in(1, kMaxGridCells);
        if (n.has("base_height")) {
            const JsonNode base = n.at("base_height");
            d.base_height = base.as_number();
            require_within(base, glm::dvec3(d.center, d.base_height), "the surface reaches");
        }
        if (n.has("generator")) parse_generator(n.at("generator"), scene_path, d, assets);
        else d.generator = HeightGenerator::Flat;
    }
    o.material = parse_material(n.at("material"));
    return o;
}

Medium parse_medium(const JsonNode& n) {
    n.check_keys({"ior", "absorption", "scattering", "anisotropy"});
    Medium m;
    m.present = true;
    if (n.has("ior")) m.ior = n.at("ior").as_positive();
    if (n.has("absorption")) m.absorption = coefficient(n.at("absorption"));
    if (n.has("scattering")) m.scattering = coefficient(n.at("scattering"));
    if (n.has("anisotropy")) m.anisotropy = n.at("anisotropy").as_number_in(-1.0, 1.0, true, true);
    return m;
}

std::string read_file(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw InputError(path, "", "the scene file does not exist");
    if (!fs::is_regular_file(path, ec)) throw InputError(path, "", "the scene path is not a regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", "the scene file cannot be opened for reading");
    std::ostringstream s;
    s << in.rdbuf();
    if (in.bad()) throw InputError(path, "", "the scene file cannot be read");
    return s.str();
}

}  // namespace

Scene load_scene(const std::string& path) {
    Scene scene;
    scene.path = path;
    scene.name = fs::path(path).stem().string();
    scene.source_text = read_file(path);

    const nlohmann::json root = parse_json_strict(scene.source_text, path);
    const JsonNode top(path, root);
    top.check_keys({"description", "fresnel", "max_specular_depth", "lights", "camera", "objects", "medium",
                    "receiver", "animation"});
    if (top.has("description")) top.at("description").as_string();
    if (top.has("fresnel")) scene.fresnel = top.at("fresnel").as_bool();
    if (top.has("max_specular_depth"))
        scene.max_specular_depth = static_cast<int>(top.at("max_specular_depth").as_integer_in(1, 1000));

    const JsonNode lights = top.at("lights");
    if (lights.array_size() == 0) lights.fail("must be a non-empty array of lights");
    for (std::size_t k = 0; k < lights.array_size(); ++k) scene.lights.push_back(parse_light(lights.at(k)));

    if (top.has("camera")) scene.camera = parse_camera(top.at("camera"));

    const JsonNode objects = top.at("objects");
    if (objects.array_size() == 0) objects.fail("must be a non-empty array of objects");
    std::set<std::string> names;
    for (std::size_t k = 0; k < objects.array_size(); ++k) {
        const JsonNode o = objects.at(k);
        scene.objects.push_back(parse_object(o, path, scene.assets));
        if (!names.insert(scene.objects.back().name).second)
            o.at("name").fail("duplicate object name '" + scene.objects.back().name + "'; names must be unique");
    }

    if (top.has("medium")) scene.medium = parse_medium(top.at("medium"));

    if (top.has("animation")) {
        const JsonNode a = top.at("animation");
        a.check_keys({"frames", "fps"});
        if (a.has("frames")) scene.animation.frames = static_cast<int>(a.at("frames").as_integer_in(1, kMaxFrames));
        if (a.has("fps")) scene.animation.fps = a.at("fps").as_number_in(0.0, 1e4, true);
    }

    const JsonNode r = top.at("receiver");
    r.check_keys({"object", "resolution"});
    const JsonNode ro = r.at("object");
    scene.receiver.object = ro.as_string();
    std::string valid;
    for (std::size_t k = 0; k < scene.objects.size(); ++k) {
        const Object& o = scene.objects[k];
        if (o.shape != ShapeType::Plane && o.shape != ShapeType::HeightField) continue;
        valid += (valid.empty() ? "" : ", ") + ("'" + o.name + "'");
        if (o.name == scene.receiver.object) scene.receiver.object_index = static_cast<int>(k);
    }
    if (scene.receiver.object_index < 0) {
        const bool exists = names.count(scene.receiver.object) > 0;
        ro.fail((exists ? "the object '" + scene.receiver.object + "' is not a plane or height field"
                        : "no object is named '" + scene.receiver.object + "'") +
                "; the receiver must name a plane or heightfield object" +
                (valid.empty() ? std::string(" (this scene has none)") : " (here: " + valid + ")"));
    }
    if (r.has("resolution")) {
        const glm::ivec2 res = r.at("resolution").as_ivec2_in(1, kMaxImageSize);
        scene.receiver.width = res.x;
        scene.receiver.height = res.y;
    }

    // The waves generator drops its seeded drops in the first half of the animation.
    for (Object& o : scene.objects)
        if (o.shape == ShapeType::HeightField)
            o.heightfield.animation_length = scene.animation.frames / scene.animation.fps;

    // The waves simulation's work to reach the last frame (heightfield_waves.cpp: CFL substeps per frame,
    // and every drop visits every vertex) must be bounded, or a frame never finishes.
    for (std::size_t k = 0; k < scene.objects.size(); ++k) {
        const HeightFieldDesc& d = scene.objects[k].heightfield;
        if (scene.objects[k].shape != ShapeType::HeightField || d.generator != HeightGenerator::Waves) continue;
        const double dx = d.size.x / d.resolution.x, dy = d.size.y / d.resolution.y;
        const double courant = d.wave_speed / scene.animation.fps * std::sqrt(1.0 / (dx * dx) + 1.0 / (dy * dy));
        const double substeps = std::max(1.0, std::ceil(courant / 0.5));
        const double vertices = (d.resolution.x + 1.0) * (d.resolution.y + 1.0);
        const double work = vertices * (substeps * std::max(1, scene.animation.frames - 1) + d.drops);
        if (!(work <= kMaxWaveUpdates))
            throw InputError(path, "objects[" + std::to_string(k) + "].generator",
                             "the wave simulation needs " + format_limit(work) + " grid updates to reach the last frame (" +
                                 format_limit(vertices) + " vertices x (" + format_limit(substeps) +
                                 " CFL substeps per frame from wave_speed, resolution and fps x " +
                                 std::to_string(std::max(1, scene.animation.frames - 1)) + " frame steps + " + std::to_string(d.drops) +
                                 " drops)); valid: at most " + format_limit(kMaxWaveUpdates) +
                                 ": lower wave_speed, drops, the resolution or the frames");
    }

    // Every resolution against the memory ceiling, before anything of that size is allocated (the
    // reference's replicas and worker threads multiply it: see limits.cpp).
    check_scene_memory(scene, kMemoryDefaultReplicas, worker_threads());
    return scene;
}

}  // namespace caustics
