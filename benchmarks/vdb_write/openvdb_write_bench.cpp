// OpenVDB's own writer, timed: reads a VDB fully into memory, then writes it
// with a chosen compression, like-for-like with aurora's writer
// (`examples/vdb_write_bench.rs` runs both and compares).
//
// Build (Debian's libopenvdb-dev, installed by tools/setup):
//   g++ -O2 -std=c++17 benchmarks/vdb_write/openvdb_write_bench.cpp -o target/openvdb_write_bench \
//       -lopenvdb -ltbb -lImath-3_1 -lpthread
//
// Usage:
//   openvdb_write_bench IN.vdb OUT.vdb MODE [--repeat N] [--half GRID]...
//   MODE: none | zip | active-mask | zip+active-mask | blosc | blosc+active-mask
//
// Prints one JSON line: {"mode", "flags", "seconds": [...], "best", "bytes"}.
//
// OpenVDB's Archive::setGridCompression drops ZIP for fog volumes and level
// sets (openvdb/io/Archive.cc), so for the ZIP modes the grid
// class is set to "unknown" before writing: the value arrays are then
// compressed exactly as aurora compresses them. Only the `class` metadata
// string differs.
#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <set>
#include <string>
#include <vector>

static int usage()
{
    std::cerr << "usage: openvdb_write_bench IN.vdb OUT.vdb "
                 "none|zip|active-mask|zip+active-mask|blosc|blosc+active-mask "
                 "[--repeat N] [--half GRID]...\n";
    return 2;
}

int main(int argc, char** argv)
{
    if (argc < 4) return usage();
    const std::string in = argv[1], out = argv[2], mode = argv[3];
    int repeat = 1;
    std::set<std::string> half;
    for (int i = 4; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
        else if (a == "--half" && i + 1 < argc) half.insert(argv[++i]);
        else return usage();
    }
    uint32_t flags;
    using namespace openvdb::io;
    if (mode == "none") flags = COMPRESS_NONE;
    else if (mode == "zip") flags = COMPRESS_ZIP;
    else if (mode == "active-mask") flags = COMPRESS_ACTIVE_MASK;
    else if (mode == "zip+active-mask") flags = COMPRESS_ZIP | COMPRESS_ACTIVE_MASK;
    else if (mode == "blosc") flags = COMPRESS_BLOSC;
    else if (mode == "blosc+active-mask") flags = COMPRESS_BLOSC | COMPRESS_ACTIVE_MASK;
    else return usage();

    openvdb::initialize();
    openvdb::GridPtrVecPtr grids;
    try {
        openvdb::io::File file(in);
        file.open(/*delayLoad=*/false); // every buffer in memory before timing
        grids = file.getGrids();
        file.close();
    } catch (const std::exception& e) {
        std::cerr << "openvdb_write_bench: reading " << in << ": " << e.what() << "\n";
        return 1;
    }
    for (auto& g : *grids) {
        if (flags & COMPRESS_ZIP) g->setGridClass(openvdb::GRID_UNKNOWN);
        if (half.count(g->getName())) g->setSaveFloatAsHalf(true);
    }

    std::vector<double> seconds;
    for (int r = 0; r < repeat; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        try {
            openvdb::io::File file(out);
            file.setCompression(flags);
            file.write(*grids);
            file.close();
        } catch (const std::exception& e) {
            std::cerr << "openvdb_write_bench: writing " << out << ": " << e.what() << "\n";
            return 1;
        }
        const auto t1 = std::chrono::steady_clock::now();
        seconds.push_back(std::chrono::duration<double>(t1 - t0).count());
    }
    std::ifstream f(out, std::ios::binary | std::ios::ate);
    const long long bytes = static_cast<long long>(f.tellg());

    std::printf("{\"mode\": \"%s\", \"flags\": %u, \"seconds\": [", mode.c_str(), flags);
    for (size_t i = 0; i < seconds.size(); ++i) std::printf("%s%.6f", i ? ", " : "", seconds[i]);
    std::printf("], \"best\": %.6f, \"bytes\": %lld}\n", *std::min_element(seconds.begin(), seconds.end()), bytes);
    return 0;
}
