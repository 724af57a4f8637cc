#pragma once
// A software G-buffer rasterizer (multiple render targets with a depth test), shared by image-space
// methods: world-space triangles are projected through a LightProjection (orthographic or perspective)
// and every covered pixel centre gets the fragment's depth, world position, unit normal and object id.
//
//   Coverage     pixel centres with the top-left fill rule on 8-bit sub-pixel fixed-point vertices (as
//                TriangleRaster's PixelCenter mode): triangles sharing an edge cover each centre once.
//   Attributes   perspective-correct barycentric interpolation (attribute / z and 1 / z interpolated
//                linearly in screen space; orthographic: linear). Positions therefore lie exactly on
//                the triangle's plane; normals are interpolated per vertex and renormalised (flat:
//                the geometric normal).
//   Culling      decided in world space, independent of the screen's handedness: a triangle is front
//                facing when its counter-clockwise normal points towards the eye (perspective) or
//                against `forward` (orthographic). CullMode::Back draws front faces only, ::Front back
//                faces only (Wyman's back-face positions for double-surface refraction).
//   Depth        view depth (LightProjection::view().z); DepthTest::Less keeps the nearest fragment,
//                ::Greater the farthest; ties keep the earlier triangle.
//   Clipping     perspective: triangles are clipped in world space against the plane at view depth
//                max(near_depth, 1e-3) (new vertices interpolate position and normal along the edges),
//                so geometry passing beside or behind a point light (cube-map faces) still rasterizes;
//                x / y are not clipped (the bounding box is clamped to the image).
//
// Parallel (TBB) over bands of rows: triangles are binned to the bands they touch in fixed-size chunks
// and each band draws its triangles in input order, so the result is identical for any thread count.
// Draw several batches (objects) into one target by calling draw() repeatedly without clearing.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/blocks/gbuffer/light_projection.hpp>

namespace caustics {

enum class CullMode { None, Back, Front };
enum class DepthTest { Less, Greater };

struct GBuffer {
    int width = 0, height = 0;
    std::vector<float> depth;           // +inf (Less) or -inf (Greater) where nothing was drawn
    std::vector<glm::vec3> position;
    std::vector<glm::vec3> normal;      // empty: not written (see clear)
    std::vector<std::int32_t> id;       // -1 where nothing was drawn
    // Sizes the buffers and clears depth and id for `test` (positions and normals are only meaningful
    // where id >= 0). Without normals the raster skips them (a positions-only target).
    void clear(int w, int h, DepthTest test = DepthTest::Less, bool with_normals = true);
    std::size_t index(int x, int y) const { return static_cast<std::size_t>(y) * width + x; }
    bool covered(std::size_t i) const { return id[i] >= 0; }
};

struct GBufferTriangles {
    std::span<const glm::vec3> positions;   // world space
    std::span<const glm::vec3> normals;     // optional, one per position (else the geometric normal)
    std::span<const glm::uvec3> triangles;  // counter-clockwise seen from the outside
    std::int32_t id = 0;                    // written to GBuffer::id
};

struct GBufferStats {
    std::int64_t triangles = 0;      // triangles in the batch
    std::int64_t culled = 0;         // rejected by the cull mode or degenerate in screen space
    std::int64_t clipped = 0;        // skipped: entirely behind the near plane, non-finite, or too far off-screen
    std::int64_t near_split = 0;     // perspective: triangles cut by the near plane (drawn in part)
    std::int64_t fragments = 0;      // pixel centres covered (before the depth test)
};

class GBufferRaster {
public:
    GBufferRaster();
    ~GBufferRaster();
    GBufferRaster(GBufferRaster&&) noexcept;
    GBufferRaster& operator=(GBufferRaster&&) noexcept;

    GBufferStats draw(const LightProjection& view, const GBufferTriangles& batch, CullMode cull, DepthTest test,
                      GBuffer& target);
    // Front faces into `front`, back faces into `back`, from one vertex and triangle set-up (the
    // double-surface pair of Wyman's refraction): the same buffers as draw(.., CullMode::Back, .., front)
    // followed by draw(.., CullMode::Front, .., back). Both targets have normals or neither. The stats
    // count the batch once (fragments of both targets).
    GBufferStats draw_front_back(const LightProjection& view, const GBufferTriangles& batch, DepthTest test,
                                 GBuffer& front, GBuffer& back);

    static constexpr int kBandRows = 16;

private:
    void clip_near(const LightProjection& view, const GBufferTriangles& batch, GBufferTriangles& eff, GBufferStats& stats);
    GBufferStats draw_clipped(const LightProjection& view, const GBufferTriangles& batch, CullMode cull, DepthTest test,
                              GBuffer& target, GBuffer* back_target, const GBufferStats& pre);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace caustics
