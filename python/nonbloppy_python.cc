// SPDX-License-Identifier: Apache-2.0
/// @file nonbloppy_python.cc
/// @brief The Python module `nonbloppy`: read particles, mesh them, write the mesh, with
///        numpy arrays in and out.
///
/// @code{.py}
/// import nonbloppy
/// particles = nonbloppy.read_particles("fluid_0023.vtk")     # or nonbloppy.Particles(array)
/// mesh = nonbloppy.build_surface(particles, attributes=["velocity"])
/// mesh.vertices, mesh.triangles, mesh.normals, mesh.attributes["velocity"]   # numpy views
/// mesh.write("fluid_0023.ply")
/// @endcode
///
/// A thin layer over the C++ library: build_surface() is nonbloppy::buildSurface() (then
/// interpolateAttributes() when asked), with the same defaults, so it gives the bytes
/// `nonbloppy mesh` gives for the same parameters (tests/python checks it). What it adds:
///  - arrays: positions of any float dtype and layout are copied once into float32, as the
///    library holds them; a mesh's and a particle set's arrays are views of the C++ object
///    (no copy), which they keep alive;
///  - threads: each call runs in a TBB arena of `threads` workers (default: the cores, or a
///    container's CPU limit, as the command-line tool), so a caller's own TBB use is left alone;
///  - the GIL is released while the library works; Ctrl-C stops the call (the library's
///    interrupter asks Python for pending signals about every 50 ms, on the calling thread),
///    as does an exception raised by a `progress` callback; either comes out of the call as
///    raised, and nothing is returned;
///  - exceptions: nonbloppy.Error (a RuntimeError), FileError (also an OSError),
///    ParameterError (also a ValueError), CancelledError; messages are the library's.

// OpenVDB's templates keep default visibility though the module builds with hidden
// visibility, as src/VisibilityPrelude.h explains (else openvdb::initialize() crashes).
#pragma GCC visibility push(default)
#include <openvdb/openvdb.h>
#include <openvdb/tools/PointIndexGrid.h>
#pragma GCC visibility pop

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/CgroupLimits.h>
#include <nonbloppy/CropParticles.h>
#include <nonbloppy/DiagnoseSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/InterpolateAttributes.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/Version.h>
#include <nonbloppy/WriteMesh.h>
#include <nonbloppy/WriteParticles.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace py = pybind11;

namespace {

/// The Python exception types, made once at import.
struct ExceptionTypes
{
    py::object error, fileError, parameterError, cancelledError;
    py::object surfaceWarning;  ///< a UserWarning: the mesh is made, but not as asked
};

ExceptionTypes& exceptionTypes()
{
    static ExceptionTypes* types = new ExceptionTypes();  // lives as long as the module
    return *types;
}

/// "(5, 2)": an array's shape as numpy prints it.
std::string shapeText(const py::array& array)
{
    std::string text = "(";
    for (py::ssize_t d = 0; d < array.ndim(); ++d) {
        if (d > 0) text += ", ";
        text += std::to_string(array.shape(d));
    }
    return text + (array.ndim() == 1 ? ",)" : ")");
}

/// @a message with the library's option names (it speaks the command line's language:
/// "--blend must lie in [0,1], got 1.5") replaced by build_surface()'s keywords.
std::string pythonNames(std::string message)
{
    static const std::pair<const char*, const char*> kNames[] = {
        {"--adaptivity", "adaptivity"}, {"--blend", "blend"}, {"--iterations", "iterations"},
        {"--max-step", "max_step"}, {"--no-smooth", "smooth=False"}, {"--radius", "radius"},
        {"--spacing", "spacing"}, {"--threshold", "threshold"}, {"--voxel-size", "voxel_size"}};
    const auto isNamePart = [](char c) { return (c >= 'a' && c <= 'z') || c == '-'; };
    for (size_t at = message.find("--"); at != std::string::npos; at = message.find("--", at + 1)) {
        for (const auto& [option, keyword] : kNames) {
            const size_t length = std::strlen(option);
            if (message.compare(at, length, option) == 0 &&
                (at + length == message.size() || !isNamePart(message[at + length]))) {
                message.replace(at, length, keyword);
                break;
            }
        }
    }
    return message;
}

/// A file name from a str or any os.PathLike (pathlib.Path), as open() takes them.
std::string pathOf(const py::object& path)
{
    const py::object name = py::module_::import("os").attr("fspath")(path);
    if (!py::isinstance<py::str>(name)) throw py::type_error("a file name must be a str or an os.PathLike of str");
    return name.cast<std::string>();
}

[[noreturn]] void throwParameterError(const std::string& message)
{
    throw nonbloppy::ParameterError(message);
}

//////////////////////////////////////// Particles

/// nonbloppy.Particles: a ParticleSet owned by Python.
struct Particles
{
    nonbloppy::ParticleSet set;
};

/// Calls @a visit with a value of each of the ten C++ types a particle attribute can hold.
template<typename VisitT>
void forEachAttributeType(VisitT&& visit)
{
    visit(int8_t()), visit(uint8_t()), visit(int16_t()), visit(uint16_t()), visit(int32_t());
    visit(uint32_t()), visit(int64_t()), visit(uint64_t()), visit(float()), visit(double());
}

py::dtype dtypeOf(nonbloppy::ScalarType type)
{
    py::dtype result;
    forEachAttributeType([&](auto value) {
        using T = decltype(value);
        if (nonbloppy::scalarTypeOf<T>() == type) result = py::dtype::of<T>();
    });
    return result;
}

/// The attribute @a name from a numpy array of shape (N,) or (N, C) with one of the ten
/// types, native byte order; the values are copied.
nonbloppy::ParticleAttribute attributeFromArray(const std::string& name, const py::handle& object, size_t count)
{
    const py::array array = py::array::ensure(object);
    if (!array) throw py::type_error("attribute '" + name + "' is not an array");
    if (array.ndim() != 1 && array.ndim() != 2) {
        throwParameterError("attribute '" + name + "' must have shape (N,) or (N, C), not " + shapeText(array));
    }
    if (size_t(array.shape(0)) != count) {
        throwParameterError("attribute '" + name + "' has " + std::to_string(array.shape(0)) + " rows for " +
                            std::to_string(count) + " particles");
    }
    const py::ssize_t components = array.ndim() == 1 ? 1 : array.shape(1);
    if (components < 1) throwParameterError("attribute '" + name + "' has 0 components, at least 1 needed");
    nonbloppy::ParticleAttribute attribute;
    bool typed = false;
    forEachAttributeType([&](auto value) {
        using T = decltype(value);
        if (typed || !py::isinstance<py::array_t<T>>(array)) return;
        typed = true;
        const auto contiguous = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(array);
        attribute.name = name;
        attribute.type = nonbloppy::scalarTypeOf<T>();
        attribute.components = int(components);
        attribute.bytes.resize(size_t(contiguous.size()) * sizeof(T));
        if (!attribute.bytes.empty()) std::memcpy(attribute.bytes.data(), contiguous.data(), attribute.bytes.size());
    });
    if (!typed) {
        throwParameterError("attribute '" + name + "' has dtype " + std::string(py::str(array.dtype())) +
                            "; a particle attribute holds int8 to int64, uint8 to uint64, float32 or float64 "
                            "in native byte order");
    }
    return attribute;
}

/// Positions from anything numpy reads as an (N, 3) array of numbers, copied into float32
/// (rounded to nearest, as the library's ParticleList adapters round).
std::vector<openvdb::Vec3f> positionsFromArray(const py::handle& object)
{
    const auto array = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(object);
    if (!array) {
        PyErr_Clear();
        throw py::type_error("positions must be an array of shape (N, 3) of numbers");
    }
    if (array.ndim() != 2 || array.shape(1) != 3) {
        throwParameterError("positions must have shape (N, 3), not " + shapeText(array));
    }
    std::vector<openvdb::Vec3f> positions(size_t(array.shape(0)));
    // Vec3f is three packed floats (OpenVDB's Tuple), as the array's rows are.
    static_assert(sizeof(openvdb::Vec3f) == 3 * sizeof(float));
    if (!positions.empty()) std::memcpy(static_cast<void*>(positions.data()), array.data(), positions.size() * sizeof(openvdb::Vec3f));
    return positions;
}

Particles makeParticles(const py::handle& positions, const std::optional<py::dict>& attributes)
{
    Particles particles;
    particles.set.positions = positionsFromArray(positions);
    if (attributes) {
        for (const auto& item : *attributes) {
            if (!py::isinstance<py::str>(item.first)) throw py::type_error("attribute names must be strings");
            const std::string name = item.first.cast<std::string>();
            if (name.empty()) throwParameterError("an attribute name is empty");
            particles.set.attributes.push_back(attributeFromArray(name, item.second, particles.set.size()));
        }
    }
    return particles;
}

/// A numpy view of @a count rows of @a columns values of type T at @a data, owned by
/// @a owner (a Python object that keeps the memory alive); shape (count,) when
/// @a columns is 1 and @a flat.
template<typename T>
py::array viewOf(const T* data, size_t count, size_t columns, const py::handle& owner, bool flat = false)
{
    if (flat && columns == 1) return py::array_t<T>({count}, {sizeof(T)}, data, owner);
    return py::array_t<T>({count, columns}, {columns * sizeof(T), sizeof(T)}, data, owner);
}

py::dict particleAttributes(const py::object& self)
{
    const Particles& particles = self.cast<const Particles&>();
    py::dict result;
    for (const nonbloppy::ParticleAttribute& attribute : particles.set.attributes) {
        const size_t count = attribute.size();
        const size_t components = size_t(attribute.components);
        const py::dtype dtype = dtypeOf(attribute.type);
        std::vector<py::ssize_t> shape{py::ssize_t(count)};
        if (components != 1) shape.push_back(py::ssize_t(components));
        const py::ssize_t itemSize = py::ssize_t(nonbloppy::scalarSize(attribute.type));
        std::vector<py::ssize_t> strides{py::ssize_t(components) * itemSize};
        if (components != 1) strides.push_back(itemSize);
        result[py::str(attribute.name)] = py::array(dtype, shape, strides, attribute.bytes.data(), self);
    }
    return result;
}

//////////////////////////////////////// Progress, Ctrl-C and threads

/// The interrupter handed to the library: on the calling thread, at each stage's start and
/// then at most every 50 ms, it takes the GIL, asks Python for pending signals (Ctrl-C) and
/// calls the progress callback. Either one's exception stops the library's work (it throws
/// CancelledError) and is raised again by rethrowPythonError().
class PythonInterrupter final : public openvdb::util::NullInterrupter
{
public:
    explicit PythonInterrupter(py::object progress)
        : mProgress(std::move(progress)), mCaller(std::this_thread::get_id()) {}

    void start(const char* name) override
    {
        if (std::this_thread::get_id() != mCaller) return;
        mStage = name ? name : "working";
        mPercent.store(-1, std::memory_order_relaxed);
        askPython();
    }

    bool wasInterrupted(int percent) override
    {
        if (percent >= 0) mPercent.store(percent, std::memory_order_relaxed);
        if (mStopped.load(std::memory_order_relaxed)) return true;
        if (std::this_thread::get_id() != mCaller) return false;
        if (std::chrono::steady_clock::now() - mAsked < std::chrono::milliseconds(50)) return false;
        askPython();
        return mStopped.load(std::memory_order_relaxed);
    }

    /// Raise the exception that stopped the work, if Python's (a signal or the callback).
    void rethrowPythonError()
    {
        if (mError) {
            std::unique_ptr<py::error_already_set> error = std::move(mError);
            throw std::move(*error);
        }
    }

private:
    void askPython()
    {
        mAsked = std::chrono::steady_clock::now();
        if (mStopped.load(std::memory_order_relaxed)) return;
        py::gil_scoped_acquire gil;
        try {
            if (PyErr_CheckSignals() != 0) throw py::error_already_set();
            if (!mProgress.is_none()) {
                const int percent = mPercent.load(std::memory_order_relaxed);
                mProgress(mStage, percent >= 0 ? py::object(py::int_(percent)) : py::object(py::none()));
            }
        } catch (py::error_already_set& e) {
            mError = std::make_unique<py::error_already_set>(std::move(e));
            mStopped.store(true, std::memory_order_relaxed);
        }
    }

    py::object mProgress;
    std::thread::id mCaller;
    std::string mStage = "working";
    std::atomic<int> mPercent{-1};
    std::atomic<bool> mStopped{false};
    std::chrono::steady_clock::time_point mAsked{};
    std::unique_ptr<py::error_already_set> mError;
};

int workerCount(const std::optional<int>& threads)
{
    if (!threads) return nonbloppy::defaultThreads().threads;
    if (*threads < 1) throwParameterError("threads must be at least 1, not " + std::to_string(*threads));
    return *threads;
}

/// Runs @a work without the GIL in an arena of @a threads workers; a Python exception that
/// stopped it (Ctrl-C, the progress callback) is raised instead of CancelledError.
template<typename WorkT>
void runReleased(int threads, PythonInterrupter& interrupter, WorkT&& work)
{
    try {
        py::gil_scoped_release release;
        tbb::task_arena arena(threads);
        arena.execute(work);
    } catch (const nonbloppy::CancelledError&) {
        interrupter.rethrowPythonError();
        throw;
    }
    interrupter.rethrowPythonError();  // raised while the last stage ended
}

//////////////////////////////////////// Mesh

/// nonbloppy.Mesh: a SurfaceResult without its density grid (SurfaceParameters::keepDensity
/// is false here).
struct Mesh
{
    nonbloppy::SurfaceResult result;
};

py::dict meshAttributes(const py::object& self)
{
    const Mesh& mesh = self.cast<const Mesh&>();
    py::dict result;
    const size_t vertices = mesh.result.mesh.points.size();
    for (const nonbloppy::MeshAttribute& attribute : mesh.result.mesh.attributes) {
        const size_t columns = size_t(attribute.components);
        result[py::str(attribute.name)] = attribute.integer
            ? viewOf(attribute.integers.data(), vertices, columns, self, /*flat=*/true)
            : viewOf(attribute.values.data(), vertices, columns, self, /*flat=*/true);
    }
    return result;
}

py::dict meshParameters(const Mesh& mesh)
{
    const nonbloppy::ResolvedParameters& p = mesh.result.parameters;
    py::dict result;
    result["spacing"] = p.spacing;
    result["radius"] = p.effectiveRadius;
    result["threshold"] = p.threshold;
    result["voxel_size"] = p.voxelSize;
    result["blend"] = p.blend;
    result["iterations"] = p.iterations;
    result["adaptivity"] = p.adaptivity;
    result["method"] = p.method == nonbloppy::Method::Paper ? "paper" : "faithful";
    result["max_step"] = p.maxStep;
    result["preserve_volume"] = p.preserveVolume;
    result["smooth"] = p.smoothSurface;
    result["spacing_given"] = p.spacingGiven;
    return result;
}

/// The keywords that make build_surface() use @a mesh's lengths on another frame, so that a
/// sequence is meshed alike (the lengths not given follow each frame's spacing estimate,
/// which moves with the fluid: flicker). As `nonbloppy mesh` advises for sequences.
py::dict pinnedParameters(const Mesh& mesh)
{
    const nonbloppy::ResolvedParameters& p = mesh.result.parameters;
    py::dict result;
    if (p.spacingGiven) result["spacing"] = p.spacing;
    result["radius"] = p.effectiveRadius;
    result["voxel_size"] = p.voxelSize;
    result["threshold"] = p.threshold;
    // The faithful step cap follows the estimate too (0: none).
    if (p.method == nonbloppy::Method::Faithful) result["max_step"] = p.maxStep;
    return result;
}

py::dict meshTimings(const Mesh& mesh)
{
    py::dict result;
    for (const auto& entry : mesh.result.timings.entries) result[py::str(entry.stage)] = entry.seconds;
    return result;
}

std::string meshRepr(const Mesh& mesh)
{
    std::string text = "<nonbloppy.Mesh: " + std::to_string(mesh.result.mesh.points.size()) + " vertices, " +
                       std::to_string(mesh.result.mesh.triangles.size()) + " triangles, " +
                       std::to_string(mesh.result.mesh.quads.size()) + " quads";
    for (const auto& attribute : mesh.result.mesh.attributes) text += ", " + attribute.name;
    return text + ">";
}

//////////////////////////////////////// build_surface

std::optional<std::vector<std::string>> attributeNames(const py::object& attributes)
{
    if (attributes.is_none()) return std::nullopt;
    if (py::isinstance<py::str>(attributes)) return std::vector<std::string>{attributes.cast<std::string>()};
    return attributes.cast<std::vector<std::string>>();
}

nonbloppy::Method methodOf(const std::string& method)
{
    if (method == "faithful") return nonbloppy::Method::Faithful;
    if (method == "paper") return nonbloppy::Method::Paper;
    throwParameterError("method must be 'faithful' or 'paper', not '" + method + "'");
}

/// Python's shortest text of @a value ("0.025", "1e+308"), as the user would type it.
std::string number(double value)
{
    return py::repr(py::float_(value)).cast<std::string>();
}

/// Warn (nonbloppy.SurfaceWarning) of what diagnoseSurface() finds in @a mesh, in the tool's
/// words but with build_surface()'s keywords. A warnings filter that turns them into errors
/// raises here.
void warnAbout(const Mesh& mesh)
{
    const nonbloppy::SurfaceDiagnostics d = nonbloppy::diagnoseSurface(mesh.result);
    const nonbloppy::ResolvedParameters& p = mesh.result.parameters;
    const size_t vertices = mesh.result.mesh.points.size();
    std::vector<std::string> messages;
    if (d.facesEndInside) {
        messages.push_back("blend=" + number(p.blend) + ", iterations=" + std::to_string(p.iterations) +
                           " relax too strongly for the threshold to be calibrated: flat faces end inside the "
                           "particles; lower blend or iterations" +
                           (p.spacingGiven ? "" : ", or give spacing to correct the volume"));
    }
    if (d.coarseFloats()) {
        messages.push_back("the particles reach " + number(d.farthestCoordinate) +
                           " from the origin, where float positions step by " + number(d.floatStep) + ", more than " +
                           (p.spacing > 0.0 ? "1/16 of the spacing " + number(p.spacing)
                                            : "1/8 of the voxel size " + number(p.voxelSize)) +
                           ": the surface is quantized there" + (d.dropletsMayVanish() ? ", and droplets may vanish" : "") +
                           "; move the particles nearer the origin");
    }
    if (d.empty) {
        messages.push_back("the mesh is empty: the density of the " + std::to_string(mesh.result.particleCount) +
                           (mesh.result.particleCount == 1 ? " particle" : " particles") + ", sampled at voxel_size " +
                           number(p.voxelSize) + ", nowhere reaches threshold " + number(p.threshold));
    }
    if (d.verticesWithoutNormal > 0) {
        messages.push_back(std::to_string(d.verticesWithoutNormal) + " of the " + std::to_string(vertices) +
                           " vertices have no normal (the faces around them have no area)" +
                           (p.blend == 1.0 ? ": blend=1 collapses droplets onto their particles; lower blend" : ""));
    }
    for (const auto& [name, count] : d.nonFiniteAttributes) {
        messages.push_back(std::to_string(count) + " of the " + std::to_string(vertices) +
                           " vertices have a NaN or infinite '" + name + "': particles near them hold such values");
    }
    for (const std::string& message : messages) {
        if (PyErr_WarnEx(exceptionTypes().surfaceWarning.ptr(), message.c_str(), 2) != 0) {
            throw py::error_already_set();
        }
    }
}

Mesh buildSurface(const py::object& input, std::optional<double> spacing, std::optional<double> radius,
                  std::optional<double> threshold, std::optional<double> voxelSize, double blend, int iterations,
                  const std::string& method, std::optional<double> maxStep, std::optional<bool> smooth,
                  double adaptivity, const py::object& attributes, std::optional<int> threads,
                  const py::object& progress)
{
    nonbloppy::SurfaceParameters params;
    params.spacing = spacing;
    params.effectiveRadius = radius;
    params.threshold = threshold;
    params.voxelSize = voxelSize;
    params.blend = blend;
    params.iterations = iterations;
    params.method = methodOf(method);
    params.maxStep = maxStep;
    params.smoothSurface = smooth;
    params.adaptivity = adaptivity;
    // Nothing here hands the grid out: it is freed as the extraction goes, and the freed
    // leaves handed back to the system (malloc_trim, as the tool does). Read, meshed and
    // written from a script, the 64x benchmark input peaked at 439 MB without the trim,
    // 345-349 MB with (the tool: 322 MB), in the same time.
    params.keepDensity = false;
    params.trimFreedMemory = true;
    const int workers = workerCount(threads);
    nonbloppy::checkParameters(params);

    const Particles* particles = py::isinstance<Particles>(input) ? &input.cast<const Particles&>() : nullptr;
    const std::optional<std::vector<std::string>> names = attributeNames(attributes);
    if (names && !particles) {
        throwParameterError("attributes need a nonbloppy.Particles (positions and their attributes), "
                            "not a bare array of positions");
    }
    if (names) nonbloppy::checkAttributes(particles->set, *names);  // before the work, not after
    if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw py::type_error("progress must be callable");

    std::vector<openvdb::Vec3f> positions = particles ? particles->set.positions : positionsFromArray(input);
    PythonInterrupter interrupter(progress);
    Mesh mesh;
    runReleased(workers, interrupter, [&] {
        nonbloppy::SurfaceResult result = nonbloppy::buildSurface(std::move(positions), params, &interrupter);
        if (names) {
            nonbloppy::ScopedStageTimer timer(result.timings, "interpolate attributes");
            nonbloppy::interpolateAttributes(result.mesh, particles->set, *names,
                                             result.parameters.effectiveRadius, &interrupter);
        }
        mesh.result = std::move(result);
    });
    warnAbout(mesh);
    return mesh;
}

const char* kBuildSurfaceDoc = R"(Mesh particles: the MPS density phi(x) = sum_j (r_e/|x - r_j| - 1) rasterized into a sparse
OpenVDB grid, its iso-surface phi = r_0 extracted, the vertices relaxed towards the
kernel-weighted mean of their particles `iterations` times, vertex normals from the faces.
The same pipeline, defaults and bytes as `nonbloppy mesh` (`nonbloppy help mesh`).

particles   a Particles, or anything numpy reads as an (N, 3) array of positions (copied
            into float32, world units)
spacing     particle spacing s; default estimated (the volume per particle inside the fluid);
            given, it also turns on the volume correction and the smoothing (faithful)
radius      effective radius r_e (default 2 s); threshold: r_0 (default calibrated);
            voxel_size: h (default s / 2); lengths in the particles' units
blend, iterations   relaxation blend c in [0, 1] and count t >= 0
method      'faithful' (default: calibrated r_0, capped steps, fold repair) or 'paper'
max_step    faithful: the farthest one relaxation step moves a vertex (default s / 2;
            0 or inf: no cap)
smooth      faithful: the edge-preserving smoothing after the volume correction (default:
            on when the spacing is given)
attributes  names of particle attributes to interpolate to the vertices, or 'all' (needs a
            Particles); Mesh.attributes then holds them
threads     worker threads (default: the cores, or a container's CPU limit); the result does
            not depend on it
progress    called as progress(stage, percent) on this thread at each stage's start and
            about every 50 ms (percent None when unknown); an exception it raises stops the
            work and comes out of build_surface. Ctrl-C stops it too (KeyboardInterrupt).

Cost: about 1 s per million particles on two cores (extraction, rasterization and the
relaxation dominate); memory: the density grid, 16 bytes per particle and the mesh.
The GIL is released while it works.
Raises ParameterError (bad parameters, non-finite or no positions), CancelledError; warns
(SurfaceWarning) where blend and iterations relax too strongly for r_0's calibration.)";

} // namespace

PYBIND11_MODULE(nonbloppy, m)
{
    m.doc() = "nonbloppy: surface meshes from fluid-simulation particles that keep thin sheets and "
              "sharp edges (read_particles, build_surface, Mesh.write).";
    m.attr("__version__") = nonbloppy::version();
    openvdb::initialize();

    // Error is a RuntimeError; FileError also an OSError, ParameterError also a ValueError, so
    // that callers catching the built-in kinds catch them.
    ExceptionTypes& types = exceptionTypes();
    const auto makeType = [&](const char* name, py::handle bases, const char* doc) {
        py::object type = py::reinterpret_steal<py::object>(
            PyErr_NewExceptionWithDoc((std::string("nonbloppy.") + name).c_str(), doc, bases.ptr(), nullptr));
        if (!type) throw py::error_already_set();
        m.attr(name) = type;
        return type;
    };
    types.error = makeType("Error", PyExc_RuntimeError, "Base of every error nonbloppy raises on purpose.");
    types.fileError = makeType("FileError", py::make_tuple(types.error, py::handle(PyExc_OSError)),
                               "A file could not be opened, read, parsed or written.");
    types.parameterError = makeType("ParameterError", py::make_tuple(types.error, py::handle(PyExc_ValueError)),
                                    "A parameter or the input data is out of range.");
    types.cancelledError = makeType("CancelledError", types.error, "The work was stopped; nothing was produced.");
    types.surfaceWarning = makeType("SurfaceWarning", PyExc_UserWarning,
                                    "The mesh was made, but not as asked (e.g. a relaxation too strong for the "
                                    "threshold's calibration).");
    py::register_local_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const nonbloppy::FileError& e) {
            PyErr_SetString(exceptionTypes().fileError.ptr(), e.what());
        } catch (const nonbloppy::ParameterError& e) {
            PyErr_SetString(exceptionTypes().parameterError.ptr(), pythonNames(e.what()).c_str());
        } catch (const nonbloppy::CancelledError& e) {
            PyErr_SetString(exceptionTypes().cancelledError.ptr(), e.what());
        } catch (const nonbloppy::Error& e) {
            PyErr_SetString(exceptionTypes().error.ptr(), e.what());
        }
    });

    py::class_<Particles>(m, "Particles",
        "Particle positions and per-particle attributes, as read_particles() reads them or as\n"
        "made from arrays: Particles(positions, attributes={'velocity': v}). positions: (N, 3),\n"
        "any float dtype, copied into float32; attributes: name -> (N,) or (N, C) array of\n"
        "int8 to int64, uint8 to uint64, float32 or float64, copied.")
        .def(py::init(&makeParticles), py::arg("positions"), py::arg("attributes") = py::none())
        .def_property_readonly("positions", [](const py::object& self) {
                const Particles& p = self.cast<const Particles&>();
                return viewOf(reinterpret_cast<const float*>(p.set.positions.data()), p.set.size(), 3, self);
            }, "(N, 3) float32 view of the positions, world units")
        .def_property_readonly("attributes", &particleAttributes,
            "dict: name -> (N,) or (N, C) view of each attribute, in the type the file stored")
        .def_property_readonly("skipped", [](const Particles& p) { return p.set.skipped; },
            "what the file holds per particle that no attribute could take, e.g. \"group 'splash'\"")
        .def("crop", [](const Particles& p, const std::array<double, 3>& lower, const std::array<double, 3>& upper) {
                const openvdb::BBoxd box(openvdb::Vec3d(lower[0], lower[1], lower[2]),
                                         openvdb::Vec3d(upper[0], upper[1], upper[2]));
                Particles kept;
                py::gil_scoped_release release;
                kept.set = nonbloppy::cropParticles(p.set, box);
                return kept;
            }, py::arg("lower"), py::arg("upper"),
            "The particles inside the box lower..upper (x, y, z each; its faces included), with their\n"
            "attributes, in order: a tank's walls and floor left out before meshing, as the tool's\n"
            "--particle-box. Raises ParameterError for a minimum above its maximum or a NaN bound.")
        .def("write", [](const Particles& p, const py::object& file) {
                const std::string path = pathOf(file);
                nonbloppy::requireParticleOutputFile(path);
                py::gil_scoped_release release;
                nonbloppy::writeParticles(p.set, path);
            }, py::arg("path"),
            "Write the particles with their attributes as .ply, .vtk, .vtu, .csv, .xyz (positions\n"
            "only) or .vdb (points), by the extension, through a temporary file renamed into place,\n"
            "as `nonbloppy convert`. Raises FileError, ParameterError.")
        .def("__len__", [](const Particles& p) { return p.set.size(); })
        .def("__repr__", [](const Particles& p) {
            std::string text = "<nonbloppy.Particles: " + std::to_string(p.set.size()) + " particles";
            for (const auto& attribute : p.set.attributes) text += ", " + attribute.name;
            return text + ">";
        });

    py::class_<Mesh>(m, "Mesh",
        "A relaxed surface mesh: arrays are views of it (no copies), valid as long as they are held.")
        // Views: changing one changes the mesh that write() writes.
        .def_property_readonly("vertices", [](const py::object& self) {
                const Mesh& mesh = self.cast<const Mesh&>();
                return viewOf(reinterpret_cast<const float*>(mesh.result.mesh.points.data()), mesh.result.mesh.points.size(), 3, self);
            }, "(V, 3) float32 vertex positions, world units")
        .def_property_readonly("normals", [](const py::object& self) {
                const Mesh& mesh = self.cast<const Mesh&>();
                return viewOf(reinterpret_cast<const float*>(mesh.result.mesh.normals.data()), mesh.result.mesh.normals.size(), 3, self);
            }, "(V, 3) float32 unit vertex normals (the normalized sum of the adjacent faces' normals)")
        .def_property_readonly("triangles", [](const py::object& self) {
                const Mesh& mesh = self.cast<const Mesh&>();
                return viewOf(reinterpret_cast<const uint32_t*>(mesh.result.mesh.triangles.data()), mesh.result.mesh.triangles.size(), 3, self);
            }, "(T, 3) uint32 vertex indices of the triangles, counter-clockwise seen from outside the\n"
               "fluid; with quads, the mesh's other polygons (faces has them all as triangles)")
        .def_property_readonly("quads", [](const py::object& self) {
                const Mesh& mesh = self.cast<const Mesh&>();
                return viewOf(reinterpret_cast<const uint32_t*>(mesh.result.mesh.quads.data()), mesh.result.mesh.quads.size(), 4, self);
            }, "(Q, 4) uint32 vertex indices, counter-clockwise seen from outside the fluid")
        .def_property_readonly("faces", [](const Mesh& mesh) {
                // As the writers split quads: triangles first, then (q0,q1,q2), (q0,q2,q3).
                const auto& triangles = mesh.result.mesh.triangles;
                const auto& quads = mesh.result.mesh.quads;
                py::array_t<uint32_t> faces({triangles.size() + 2 * quads.size(), size_t(3)});
                uint32_t* out = faces.mutable_data();
                for (const openvdb::Vec3I& t : triangles) out = std::copy(t.asPointer(), t.asPointer() + 3, out);
                for (const openvdb::Vec4I& q : quads) {
                    const uint32_t split[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
                    out = std::copy(split, split + 6, out);
                }
                return faces;
            }, "(T + 2Q, 3) uint32: every polygon as triangles, quads split as the writers split them\n"
               "(a new array; triangles and quads are views)")
        .def_property_readonly("attributes", &meshAttributes,
            "dict: name -> (V,) or (V, C) view: float32 means, or int64 for integer attributes (the\n"
            "nearest particle's value)")
        .def_property_readonly("parameters", &meshParameters,
            "dict of every parameter as used: spacing, radius, threshold, voxel_size, blend, ...")
        .def_property_readonly("pinned_parameters", &pinnedParameters,
            "dict of the keywords that mesh another frame with this mesh's lengths (radius,\n"
            "voxel_size, threshold, max_step; spacing where given): build_surface(frame,\n"
            "**first.pinned_parameters). Unpinned, they follow each frame's spacing estimate, which\n"
            "moves with the fluid, and the surface flickers in a rendered sequence.")
        .def_property_readonly("timings", &meshTimings, "dict: stage -> wall-clock seconds")
        .def("measure", [](const Mesh& mesh) {
                nonbloppy::MeshMeasures m;
                {
                    py::gil_scoped_release release;
                    m = nonbloppy::measureMesh(mesh.result.mesh);
                }
                py::dict result;
                result["vertices"] = m.vertices;
                result["polygons"] = m.polygons;
                result["closed"] = m.closed;
                result["manifold"] = m.manifold;
                result["area"] = m.area;
                result["volume"] = m.volume;
                result["boundary_edges"] = m.boundaryEdges;
                result["non_manifold_edges"] = m.nonManifoldEdges;
                result["inconsistent_edges"] = m.inconsistentEdges;
                result["zero_area_polygons"] = m.zeroAreaPolygons;
                result["unused_vertices"] = m.unusedVertices;
                return result;
            },
            "dict of the mesh's measures, as `nonbloppy inspect` prints them: closed, manifold (every edge\n"
            "shared by two consistently oriented polygons), area (world units^2), volume (signed,\n"
            "positive facing outwards), and the counts of boundary, non-manifold and inconsistent\n"
            "edges, zero-area polygons and unused vertices. Cost: O(polygons), about 1 s for 4.7M\n"
            "triangles on two cores.")
        .def_property_readonly("particle_count", [](const Mesh& mesh) { return mesh.result.particleCount; })
        .def("write", [](const Mesh& mesh, const py::object& file, bool quads, bool directIo) {
                const std::string path = pathOf(file);
                nonbloppy::requireMeshFile(path);
                nonbloppy::MeshWriteSettings settings;
                settings.keepQuads = quads;
                settings.directIo = directIo;
                py::gil_scoped_release release;
                nonbloppy::writeMesh(mesh.result.mesh, path, settings);
            }, py::arg("path"), py::kw_only(), py::arg("quads") = false, py::arg("direct_io") = true,
            "Write the mesh as .obj, .ply (binary) or .vtk, by the extension, through a temporary\n"
            "file renamed into place (no partial file). quads=True keeps quads. Raises FileError.")
        .def("__repr__", &meshRepr);

    m.def("read_particles", [](const py::object& file) {
            const std::string path = pathOf(file);
            Particles particles;
            {
                py::gil_scoped_release release;
                particles.set = nonbloppy::readParticles(path);
            }
            return particles;
        }, py::arg("path"),
        "Read a particle file: .vtk, .vtu/.vtp, .ply, classic .bgeo/.bhclassic (gzipped too), .vdb\n"
        "points, .csv/.txt, .json, .xyz (`nonbloppy help mesh` lists them); every attribute is\n"
        "kept in its stored type. Raises FileError naming the file and what is wrong.");

    m.def("build_surface", &buildSurface, py::arg("particles"), py::kw_only(),
          py::arg("spacing") = py::none(), py::arg("radius") = py::none(), py::arg("threshold") = py::none(),
          py::arg("voxel_size") = py::none(), py::arg("blend") = nonbloppy::kDefaultBlend,
          py::arg("iterations") = nonbloppy::kDefaultIterations, py::arg("method") = "faithful",
          py::arg("max_step") = py::none(), py::arg("smooth") = py::none(),
          py::arg("adaptivity") = nonbloppy::kDefaultAdaptivity, py::arg("attributes") = py::none(),
          py::arg("threads") = py::none(), py::arg("progress") = py::none(), kBuildSurfaceDoc);
}
