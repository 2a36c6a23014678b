// SPDX-License-Identifier: Apache-2.0
/// @file bench_stages.cc
/// @brief Google Benchmark micro-benchmarks, one per pipeline stage, on the real dam-break
///        frame tiled 2×2×2 in memory (195,112 particles), h = 0.025, r_e = 0.1, c = 0.3.
///
///     cmake -S . -B build -DNONBLOPPY_BUILD_BENCHMARKS=ON && cmake --build build --target nonbloppy_bench
///     build/nonbloppy_bench --benchmark_counters_tabular=true
///
/// Each benchmark reports items per second (particles for index/rasterize, vertices for the
/// mesh stages; smoothSurface runs only when the spacing is given). Not a test: timings
/// depend on the machine; ratios between stages are the point.

#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/RelaxVertices.h>
#include <nonbloppy/SmoothSurface.h>
#include <nonbloppy/WriteMesh.h>

#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>
#include <unistd.h>

namespace {

constexpr double kVoxelSize = 0.025;
constexpr double kEffectiveRadius = 0.1;
constexpr double kThreshold = 7.85;  // about calibrateThreshold(2): r_e = 2 × the 0.05 rest spacing

/// The frame, tiled 2×2×2 with gaps, computed once.
const std::vector<openvdb::Vec3f>& particles()
{
    static const std::vector<openvdb::Vec3f> tiled = [] {
        const nonbloppy::ParticleSet frame =
            nonbloppy::readParticles(std::string(NONBLOPPY_TEST_DATA_DIR) + "/dam_break_frame_23_24389_particles.vtk");
        openvdb::BBoxd bounds;
        for (const auto& p : frame.positions) bounds.expand(openvdb::Vec3d(p));
        const openvdb::Vec3d step = bounds.extents() + openvdb::Vec3d(0.05);
        std::vector<openvdb::Vec3f> out;
        for (int i = 0; i < 2; ++i)
            for (int j = 0; j < 2; ++j)
                for (int k = 0; k < 2; ++k)
                    for (const auto& p : frame.positions)
                        out.push_back(p + openvdb::Vec3f(float(i * step[0]), float(j * step[1]), float(k * step[2])));
        return out;
    }();
    return tiled;
}

const nonbloppy::ParticleIndex& particleIndex()
{
    static const nonbloppy::ParticleIndex index = nonbloppy::ParticleIndex::build(particles(), kEffectiveRadius / 2);
    return index;
}

nonbloppy::DensitySettings densitySettings()
{
    nonbloppy::DensitySettings settings;
    settings.effectiveRadius = kEffectiveRadius;
    settings.voxelSize = kVoxelSize;
    return settings;
}

const openvdb::FloatGrid& density()
{
    static const openvdb::FloatGrid::Ptr grid = nonbloppy::rasterizeDensity(particleIndex(), densitySettings());
    return *grid;
}

const nonbloppy::SurfaceMesh& unrelaxedMesh()
{
    static const nonbloppy::SurfaceMesh mesh = nonbloppy::extractSurface(density(), kThreshold);
    return mesh;
}

void indexParticles(benchmark::State& state)
{
    for (auto _ : state) {
        benchmark::DoNotOptimize(nonbloppy::ParticleIndex::build(particles(), kEffectiveRadius / 2).size());
    }
    state.SetItemsProcessed(int64_t(state.iterations() * particles().size()));
}

void rasterizeDensity(benchmark::State& state)
{
    particleIndex();
    for (auto _ : state) {
        benchmark::DoNotOptimize(nonbloppy::rasterizeDensity(particleIndex(), densitySettings()));
    }
    state.SetItemsProcessed(int64_t(state.iterations() * particles().size()));
}

void extractSurface(benchmark::State& state)
{
    density();
    for (auto _ : state) {
        benchmark::DoNotOptimize(nonbloppy::extractSurface(density(), kThreshold).points.size());
    }
    state.SetItemsProcessed(int64_t(state.iterations() * unrelaxedMesh().points.size()));
}

/// One relaxation iteration (t = 1); the pipeline's cost grows linearly with t.
void relaxVertices(benchmark::State& state)
{
    nonbloppy::RelaxSettings settings;
    settings.effectiveRadius = kEffectiveRadius;
    settings.blend = 0.3;
    settings.iterations = 1;
    for (auto _ : state) {
        state.PauseTiming();
        nonbloppy::SurfaceMesh mesh = unrelaxedMesh();
        state.ResumeTiming();
        nonbloppy::relaxVertices(mesh, particleIndex(), settings);
        benchmark::DoNotOptimize(mesh.points.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations() * unrelaxedMesh().points.size()));
}

/// The default smoothing (35 normal rounds, 40 vertex rounds) at s = 0.05 (the frame's rest
/// spacing), as buildSurface() runs it when the spacing is given.
void smoothSurface(benchmark::State& state)
{
    nonbloppy::SmoothSettings settings;
    settings.spatialWidth = nonbloppy::kDefaultSmoothWidthOverSpacing * 0.05;
    for (auto _ : state) {
        state.PauseTiming();
        nonbloppy::SurfaceMesh mesh = unrelaxedMesh();
        state.ResumeTiming();
        nonbloppy::smoothSurface(mesh, settings);
        benchmark::DoNotOptimize(mesh.points.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations() * unrelaxedMesh().points.size()));
}

void computeNormals(benchmark::State& state)
{
    nonbloppy::SurfaceMesh mesh = unrelaxedMesh();
    for (auto _ : state) {
        nonbloppy::computeNormals(mesh);
        benchmark::DoNotOptimize(mesh.normals.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations() * mesh.points.size()));
}

void writeMesh(benchmark::State& state)
{
    nonbloppy::SurfaceMesh mesh = unrelaxedMesh();
    nonbloppy::computeNormals(mesh);
    const std::string path = "/tmp/nonbloppy_bench_" + std::to_string(getpid()) + ".ply";
    for (auto _ : state) nonbloppy::writeMesh(mesh, path);
    std::remove(path.c_str());
    state.SetItemsProcessed(int64_t(state.iterations() * mesh.points.size()));
}

} // namespace

BENCHMARK(indexParticles)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(rasterizeDensity)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(extractSurface)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(relaxVertices)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(smoothSurface)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(computeNormals)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(writeMesh)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
