// OpenSubdiv side of the subdivision benchmark (tessd vs OpenSubdiv on the same cages).
//
// Reads an OBJ cage (v and f records only), refines it uniformly to each level F..N with
// OpenSubdiv 3.5 (Debian libosd-dev) and prints one JSON object per level on stdout.
// Every level is refined from the cage again (a fresh TopologyRefiner per run), and each
// timing is the median of the runs (--repeat, cut short by --budget). See
// bench/subdiv/README.md for what each timing means.
//
//   osd_bench CAGE.obj [--levels N] [--first-level F] [--scheme catmark|loop]
//             [--boundary edge-only|edge-and-corner] [--repeat R] [--budget SECONDS]
//             [--dump-obj PATH]
//
// Build: bash bench/subdiv/setup_osd.sh   (g++ -O2 ... -losdCPU)

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefiner.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#include <opensubdiv/osd/bufferDescriptor.h>
#include <opensubdiv/osd/cpuEvaluator.h>
#include <opensubdiv/osd/cpuVertexBuffer.h>
#include <opensubdiv/version.h>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace OpenSubdiv;

namespace {

struct Vertex {
    float p[3];
    void Clear(void * = nullptr) { p[0] = p[1] = p[2] = 0.0f; }
    void AddWithWeight(Vertex const &src, float w) {
        p[0] += w * src.p[0];
        p[1] += w * src.p[1];
        p[2] += w * src.p[2];
    }
};

struct Cage {
    std::vector<float> positions;  // xyz per vertex
    std::vector<int> faceSizes;
    std::vector<int> faceIndices;
    int numVertices() const { return (int)(positions.size() / 3); }
    int numFaces() const { return (int)faceSizes.size(); }
};

[[noreturn]] void die(const std::string &msg) {
    std::fprintf(stderr, "osd_bench: %s\n", msg.c_str());
    std::exit(2);
}

// OBJ reader: "v x y z" and "f a b c ..." (a may be a, a/b, a//c, a/b/c; negative indices are
// relative to the vertices read so far). Everything else is ignored.
Cage readObj(const std::string &path) {
    std::ifstream in(path);
    if (!in) die("cannot open " + path);
    Cage cage;
    std::string line;
    int lineNo = 0;
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.size() < 2) continue;
        if (line[0] == 'v' && (line[1] == ' ' || line[1] == '\t')) {
            std::istringstream ss(line.substr(2));
            float x, y, z;
            if (!(ss >> x >> y >> z)) die(path + ":" + std::to_string(lineNo) + ": bad vertex");
            cage.positions.push_back(x);
            cage.positions.push_back(y);
            cage.positions.push_back(z);
        } else if (line[0] == 'f' && (line[1] == ' ' || line[1] == '\t')) {
            std::istringstream ss(line.substr(2));
            std::string tok;
            int n = 0;
            while (ss >> tok) {
                long idx = std::strtol(tok.c_str(), nullptr, 10);  // stops at '/'
                if (idx == 0) die(path + ":" + std::to_string(lineNo) + ": bad face index");
                long nv = (long)cage.numVertices();
                long i = idx > 0 ? idx - 1 : nv + idx;
                if (i < 0) die(path + ":" + std::to_string(lineNo) + ": face index out of range");
                cage.faceIndices.push_back((int)i);
                ++n;
            }
            if (n < 3) die(path + ":" + std::to_string(lineNo) + ": face with fewer than 3 vertices");
            cage.faceSizes.push_back(n);
        }
    }
    for (int i : cage.faceIndices)
        if (i >= cage.numVertices()) die(path + ": face index beyond the vertex count");
    if (cage.faceSizes.empty()) die(path + ": no faces");
    return cage;
}

double medianOf(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0, Clock::time_point t1) {
    return std::chrono::duration<double, std::milli>(t1 - t0).count();
}

// Current resident set in kilobytes (VmRSS of /proc/self/status); 0 when unavailable.
long currentRssKb() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.compare(0, 6, "VmRSS:") == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
    return 0;
}

long peakRssKb() {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss;  // kilobytes on Linux
}

std::string jsonEscape(const std::string &s) {
    std::string o;
    for (char c : s) {
        if (c == '"' || c == '\\') { o += '\\'; o += c; }
        else if ((unsigned char)c < 0x20) { char b[8]; std::snprintf(b, sizeof b, "\\u%04x", c); o += b; }
        else o += c;
    }
    return o;
}

std::string baseName(const std::string &p) {
    size_t s = p.find_last_of('/');
    return s == std::string::npos ? p : p.substr(s + 1);
}

void usage() {
    std::fprintf(stderr,
                 "usage: osd_bench CAGE.obj [--levels N (1..6, default 4)] [--first-level F (default 1)]\n"
                 "                 [--scheme catmark|loop] [--boundary edge-only|edge-and-corner]\n"
                 "                 [--repeat R (default 5)] [--budget SECONDS (default: none)]\n"
                 "                 [--dump-obj PATH]\n");
    std::exit(2);
}

}  // namespace

int main(int argc, char **argv) {
    std::string cagePath, schemeName = "catmark", boundaryName = "edge-and-corner", dumpPath;
    int maxLevel = 4, firstLevel = 1, repeat = 5;
    double budget = -1.0;  // seconds per level; < 0: no budget
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) usage();
            return argv[++i];
        };
        if (a == "--levels") maxLevel = std::atoi(next().c_str());
        else if (a == "--scheme") schemeName = next();
        else if (a == "--boundary") boundaryName = next();
        else if (a == "--first-level") firstLevel = std::atoi(next().c_str());
        else if (a == "--repeat") repeat = std::atoi(next().c_str());
        else if (a == "--budget") budget = std::atof(next().c_str());
        else if (a == "--dump-obj") dumpPath = next();
        else if (a == "-h" || a == "--help") usage();
        else if (!a.empty() && a[0] == '-') usage();
        else if (cagePath.empty()) cagePath = a;
        else usage();
    }
    if (cagePath.empty()) usage();
    if (maxLevel < 1 || maxLevel > 6) die("--levels must be 1..6");
    if (firstLevel < 1 || firstLevel > maxLevel) die("--first-level must be 1..--levels");
    if (repeat < 1) die("--repeat must be >= 1");

    Sdc::SchemeType scheme;
    if (schemeName == "catmark") scheme = Sdc::SCHEME_CATMARK;
    else if (schemeName == "loop") scheme = Sdc::SCHEME_LOOP;
    else die("--scheme must be catmark or loop");

    Sdc::Options sdcOptions;
    if (boundaryName == "edge-only")
        sdcOptions.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
    else if (boundaryName == "edge-and-corner")
        sdcOptions.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
    else die("--boundary must be edge-only or edge-and-corner");

    Cage cage = readObj(cagePath);
    // Baseline for peak_over_baseline_kb: the process with its cage read, before any refinement.
    const long baselineRssKb = currentRssKb();
    if (scheme == Sdc::SCHEME_LOOP)
        for (int n : cage.faceSizes)
            if (n != 3) die("loop scheme needs a triangle cage (found a face with " + std::to_string(n) + " vertices)");

    Far::TopologyDescriptor desc;
    desc.numVertices = cage.numVertices();
    desc.numFaces = cage.numFaces();
    desc.numVertsPerFace = cage.faceSizes.data();
    desc.vertIndicesPerFace = cage.faceIndices.data();

    typedef Far::TopologyRefinerFactory<Far::TopologyDescriptor> Factory;
    const Factory::Options factoryOptions(scheme, sdcOptions);
    const int nCage = cage.numVertices();

    for (int level = firstLevel; level <= maxLevel; ++level) {
        std::vector<double> tCreate, tRefine, tTopo, tPrimvar, tStencilBuild, tStencilEval;
        long outVertices = 0, outFaces = 0;
        int numStencils = 0;
        double maxDiff = 0.0;

        int runs = 0;
        auto levelStart = Clock::now();
        for (int r = 0; r < repeat; ++r) {
            // Budget: stop when another run like the last one would end past it (one run at least).
            if (r > 0 && budget >= 0.0) {
                double spent = msSince(levelStart, Clock::now()) / 1000.0;
                if (spent + spent / r > budget) break;
            }
            ++runs;
            // --- topology: create + uniform refinement ---------------------------------------
            auto t0 = Clock::now();
            std::unique_ptr<Far::TopologyRefiner> refiner(Factory::Create(desc, factoryOptions));
            auto t1 = Clock::now();
            if (!refiner) die("TopologyRefinerFactory::Create failed");
            refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(level));
            auto t2 = Clock::now();
            tCreate.push_back(msSince(t0, t1));
            tRefine.push_back(msSince(t1, t2));
            tTopo.push_back(msSince(t0, t2));

            Far::TopologyLevel const &last = refiner->GetLevel(level);
            outVertices = last.GetNumVertices();
            outFaces = last.GetNumFaces();

            // --- primvar: PrimvarRefiner::Interpolate of positions through all levels --------
            // The buffer for all levels is allocated (untimed) before; the cage is copied in.
            std::vector<Vertex> verts(refiner->GetNumVerticesTotal());
            std::memcpy(verts.data(), cage.positions.data(), sizeof(float) * 3 * nCage);
            auto t3 = Clock::now();
            {
                Far::PrimvarRefiner primvar(*refiner);
                Vertex *src = verts.data();
                for (int l = 1; l <= level; ++l) {
                    Vertex *dst = src + refiner->GetLevel(l - 1).GetNumVertices();
                    primvar.Interpolate(l, src, dst);
                    src = dst;
                }
            }
            auto t4 = Clock::now();
            tPrimvar.push_back(msSince(t3, t4));
            const Vertex *lastVerts = verts.data() + (refiner->GetNumVerticesTotal() - outVertices);

            // --- stencils: table build (last level only, offsets on) ------------------------
            Far::StencilTableFactory::Options stOptions;
            stOptions.generateIntermediateLevels = false;
            stOptions.generateOffsets = true;
            stOptions.generateControlVerts = false;
            stOptions.maxLevel = level;
            auto t5 = Clock::now();
            std::unique_ptr<Far::StencilTable const> stencils(Far::StencilTableFactory::Create(*refiner, stOptions));
            auto t6 = Clock::now();
            tStencilBuild.push_back(msSince(t5, t6));
            numStencils = stencils->GetNumStencils();
            if (numStencils != outVertices) die("stencil count differs from the last level's vertex count");

            // --- stencil eval: Osd::CpuEvaluator::EvalStencils with CpuVertexBuffers --------
            std::unique_ptr<Osd::CpuVertexBuffer> srcBuf(Osd::CpuVertexBuffer::Create(3, nCage));
            std::unique_ptr<Osd::CpuVertexBuffer> dstBuf(Osd::CpuVertexBuffer::Create(3, numStencils));
            srcBuf->UpdateData(cage.positions.data(), 0, nCage);
            Osd::BufferDescriptor srcDesc(0, 3, 3), dstDesc(0, 3, 3);
            auto t7 = Clock::now();
            bool ok = Osd::CpuEvaluator::EvalStencils(srcBuf.get(), srcDesc, dstBuf.get(), dstDesc, stencils.get());
            auto t8 = Clock::now();
            if (!ok) die("CpuEvaluator::EvalStencils failed");
            tStencilEval.push_back(msSince(t7, t8));

            // Cross-check (untimed): stencil result == PrimvarRefiner result.
            if (r == 0) {
                const float *out = dstBuf->BindCpuBuffer();
                for (long i = 0; i < outVertices; ++i)
                    for (int k = 0; k < 3; ++k)
                        maxDiff = std::max(maxDiff, (double)std::fabs(out[3 * i + k] - lastVerts[i].p[k]));
            }

            // --- optional dump of the refined mesh at the last level --------------------------
            if (r == 0 && level == maxLevel && !dumpPath.empty()) {
                FILE *f = std::fopen(dumpPath.c_str(), "w");
                if (!f) die("cannot write " + dumpPath);
                std::fprintf(f, "# osd_bench: %s, %s, %s, level %d (OpenSubdiv %d)\n", baseName(cagePath).c_str(),
                             schemeName.c_str(), boundaryName.c_str(), level, OPENSUBDIV_VERSION_NUMBER);
                for (long i = 0; i < outVertices; ++i)
                    std::fprintf(f, "v %.9g %.9g %.9g\n", lastVerts[i].p[0], lastVerts[i].p[1], lastVerts[i].p[2]);
                for (long fi = 0; fi < outFaces; ++fi) {
                    Far::ConstIndexArray fv = last.GetFaceVertices((Far::Index)fi);
                    std::fputc('f', f);
                    for (int k = 0; k < fv.size(); ++k) std::fprintf(f, " %d", fv[k] + 1);
                    std::fputc('\n', f);
                }
                std::fclose(f);
            }
        }

        double topo = medianOf(tTopo);
        std::printf(
            "{\"cage\": \"%s\", \"scheme\": \"%s\", \"boundary\": \"%s\", \"level\": %d, "
            "\"cage_vertices\": %d, \"cage_faces\": %d, \"out_vertices\": %ld, \"out_faces\": %ld, "
            "\"topology_ms\": %.4f, \"create_ms\": %.4f, \"refine_ms\": %.4f, \"primvar_ms\": %.4f, "
            "\"stencil_build_ms\": %.4f, \"stencil_eval_ms\": %.4f, \"topology_vertices_per_s\": %.1f, "
            "\"stencil_vs_primvar_max_abs\": %.3g, \"repeat\": %d, \"osd_version\": \"%d.%d.%d\", "
            "\"peak_rss_kb\": %ld, \"baseline_rss_kb\": %ld, \"peak_over_baseline_kb\": %ld}\n",
            jsonEscape(baseName(cagePath)).c_str(), schemeName.c_str(), boundaryName.c_str(), level,
            cage.numVertices(), cage.numFaces(), outVertices, outFaces, topo, medianOf(tCreate),
            medianOf(tRefine), medianOf(tPrimvar), medianOf(tStencilBuild), medianOf(tStencilEval),
            topo > 0 ? outVertices / (topo / 1000.0) : 0.0, maxDiff, runs, OPENSUBDIV_VERSION_MAJOR,
            OPENSUBDIV_VERSION_MINOR, OPENSUBDIV_VERSION_PATCH, peakRssKb(), baselineRssKb,
            peakRssKb() - baselineRssKb);
        std::fflush(stdout);
    }
    return 0;
}
