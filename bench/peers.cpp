#include "benchmarks.hpp"
namespace tumble_bench { void run_peers(const Options&) {} }
