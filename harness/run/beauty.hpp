#pragma once
// The beauty image for figures (not part of any error): camera rays through the RayTracer; at diffuse
// hits, albedo / pi * (direct irradiance from every light, with shadow rays, + caustic irradiance E_c).
// Specular objects cast shadows, since their light arrives as caustics (docs/design.md section 3). E_c at
// primary diffuse hits comes from the method's camera view; at diffuse hits reached through specular
// surfaces, from the method's receiver map when the hit is on the measurement receiver (elsewhere 0).
// Mirrors reflect; dielectrics refract (Fresnel-weighted reflection + refraction when scene.fresnel,
// refraction only otherwise; total internal reflection reflects), up to scene.max_specular_depth.
// Misses see a simple sky. Dispersion is ignored here (the base ior is used).
#include <string>

#include <caustics/frame/camera.hpp>
#include <caustics/util/image.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/frame/ray_tracer.hpp>

namespace caustics {

struct BeautyInputs {
    const CameraGBuffer* gbuffer = nullptr;   // the G-buffer the camera view was computed on
    const Image* camera_ec = nullptr;         // E_c per camera pixel (method output), may be null/empty
    const ReceiverChart* chart = nullptr;     // the measurement receiver's chart
    const Image* receiver_ec = nullptr;       // E_c per receiver bin (method output), may be null/empty
    int samples_per_axis = 2;                 // stratified sub-pixel samples per axis
};

// 3-channel linear radiance image of the scene camera's size.
Image render_beauty(const RayTracer& tracer, const BeautyInputs& inputs);

// An exposure that makes the image readable: the 97th percentile of non-zero luminance maps to 0.85.
double beauty_exposure(const Image& linear);

// write_png with beauty_exposure.
void write_beauty_png(const Image& linear, const std::string& path);

}  // namespace caustics
