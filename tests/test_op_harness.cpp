// The op harness (tests/op_harness/): every row of the table against its reference with its tolerance, every buffer
// guarded; one test case per op family, the tiny rows once more as the oclgrind subset; the table covers every
// public entry point host/src/ops/*.hpp declares and every graph node kind (both enumerated from the library); and
// the guard check itself fails where it must. NGI_OP_HARNESS_REPORT=1 prints every case's
// normalized error (how docs/RELIABILITY.md's "Op harness" figures were measured).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string_view>

#include "op_harness/guarded_buffer.hpp"
#include "graph/node_kind.hpp"
#include "op_harness/op_cases.hpp"
#include "ops/elementwise.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::harness;

namespace {

bool starts_with_any(const std::string& op, std::initializer_list<const char*> prefixes) {
    for (const char* p : prefixes)
        if (op.rfind(p, 0) == 0) return true;
    return false;
}

// Runs the rows of the given ops (tiny rows only, or the others), each checked on its own.
void run_rows(std::initializer_list<const char*> ops, bool tiny) {
    const bool report = std::getenv("NGI_OP_HARNESS_REPORT") != nullptr;
    int ran = 0;
    for (const OpCase& c : op_cases()) {
        if (c.tiny != tiny || (ops.size() && !starts_with_any(c.op, ops))) continue;
        const Outcome o = run_case(test::ctx(), c, Size::Test);
        ++ran;
        if (report)
            std::printf("op_harness %-44s %-44s %-40s error %.3g tolerance %.3g\n", c.op.c_str(), c.name.c_str(),
                        o.shape.c_str(), o.error, c.tolerance);
        INFO(c.id() << " [" << o.shape << "]: normalized error " << o.error << ", tolerance " << c.tolerance
                    << (o.failure.empty() ? "" : "; " + o.failure) << "; " << o.worst);
        CHECK(o.failure.empty());
        CHECK(o.error <= c.tolerance);
    }
    REQUIRE(ran > 0);
}

// C++ text with comments, string and character literals and preprocessor lines blanked out.
std::string code_only(const std::string& s) {
    std::string out;
    for (std::size_t i = 0; i < s.size(); ++i) {
        const bool line_start = out.empty() || out.find_last_not_of(" \t") == std::string::npos ||
                                out[out.find_last_not_of(" \t")] == '\n';
        if (s.compare(i, 2, "//") == 0 || (s[i] == '#' && line_start)) {
            while (i < s.size() && s[i] != '\n') ++i;
            out += '\n';
        } else if (s.compare(i, 2, "/*") == 0) {
            i = s.find("*/", i + 2);
            if (i == std::string::npos) break;
            ++i;
            out += ' ';
        } else if (s[i] == '"' || s[i] == '\'') {
            const char q = s[i];
            for (++i; i < s.size() && s[i] != q; ++i)
                if (s[i] == '\\') ++i;
            out += "0";
        } else {
            out += s[i];
        }
    }
    return out;
}

// The public entry points a header declares: every member function of a class or struct (not nested in another)
// that is public, not static, not const, not a constructor, and takes `Context& ctx` first: "Class::method", in order.
std::vector<std::string> entry_points_in(const std::string& text) {
    const std::string code = code_only(text);
    static const std::regex head(R"(^\s*(class|struct)\s+(\w+)[^(=]*$)");
    static const std::regex member(R"((?:^|[\s*&])(~?\w+)\s*\(\s*Context\s*&)");
    static const std::regex access(R"(^\s*(public|private|protected)\s*$)");
    static const std::regex qualifier(R"(^\s*(static|friend)\b)");
    std::vector<std::string> found;
    std::string cls, statement;
    bool is_public = false;
    int depth = 0, body = -1;  // body: the depth of the class's members
    for (std::size_t i = 0; i < code.size(); ++i) {
        const char ch = code[i];
        std::smatch m;
        if (ch == ':' && depth == body && code[i + 1] != ':' && std::regex_search(statement, m, access)) {
            is_public = m[1] == "public";
            statement.clear();
        } else if (ch == '{' || ch == ';' || ch == '}') {
            if (ch == '{' && cls.empty() && std::regex_search(statement, m, head)) {
                cls = m[2];
                is_public = m[1] == "struct";
                body = depth + 1;
            } else if (ch != '}' && depth == body && is_public && std::regex_search(statement, m, member) &&
                       m[1] != cls && m[1] != "~" + cls && !std::regex_search(statement, qualifier) &&
                       statement.find("const", statement.rfind(')')) == std::string::npos) {
                found.push_back(cls + "::" + std::string(m[1]));
            }
            depth += ch == '{' ? 1 : ch == '}' ? -1 : 0;
            if (depth < body) {
                cls.clear();
                body = -1;
            }
            statement.clear();
        } else {
            statement += ch;
        }
    }
    return found;
}

// Every entry point host/src/ops/*.hpp declares -> its header.
std::map<std::string, std::string> declared_entry_points() {
    namespace fs = std::filesystem;
    std::map<std::string, std::string> all;
    for (const fs::directory_entry& e : fs::directory_iterator(fs::path(NGI_SOURCE_DIR) / "host" / "src" / "ops")) {
        if (e.path().extension() != ".hpp") continue;
        std::ifstream f(e.path());
        std::stringstream text;
        text << f.rdbuf();
        for (const std::string& name : entry_points_in(text.str())) all[name] = e.path().filename().string();
    }
    return all;
}

// The entry points a row of the table covers: its op, "Class::a + b" for a row that checks two together.
std::vector<std::string> entry_points_of_row(const std::string& op) {
    std::vector<std::string> names;
    const std::string cls = op.substr(0, op.find("::") + 2);
    std::size_t at = 0;
    for (;;) {
        const std::size_t plus = op.find(" + ", at);
        std::string part = op.substr(at, plus == std::string::npos ? std::string::npos : plus - at);
        names.push_back(part.find("::") == std::string::npos ? cls + part : part);
        if (plus == std::string::npos) return names;
        at = plus + 3;
    }
}

// Entry points that are the implementation of others and reached only through them, each with the rows that take
// that path (their names say so). A class the ops use inside another op, not a separate op.
struct ReachedThrough {
    std::vector<std::string> owners;
    std::string rows;  // a part of those rows' names
};
const std::map<std::string, ReachedThrough> kReachedThrough = {
    {"ImplicitConv::enqueue", {{"Conv2d::enqueue", "ConvTranspose2d::enqueue"}, "implicit"}},
};

// The entry points each graph node kind's adapter enqueues (graph/nodes.hpp, made by models/graph_model.cpp's
// make_node_op), for every kind of graph/node_kind.hpp.
const std::map<std::string_view, std::vector<const char*>> kNodeKindOps = {
    {"conv2d", {"Conv2d::enqueue"}},
    {"conv_transpose2d", {"ConvTranspose2d::enqueue"}},
    {"dense", {"Conv2d::enqueue"}},  // a 1 x 1 convolution
    {"concat", {}},                  // Graph::concat: the inputs placed side by side, no kernel
    {"activation", {"Elementwise::activate"}},
    {"affine", {"Elementwise::channel_affine"}},
    {"add", {"Elementwise::add", "Elementwise::channel_affine"}},  // BinaryNode; BroadcastNode
    {"mul", {"Elementwise::mul", "Elementwise::channel_affine"}},
    {"frequency_encode", {"FrequencyEncodePlanar::enqueue"}},
    {"nan_to_num", {"Elementwise::sanitize"}},
    {"max_pool2d", {"MaxPool2d::enqueue"}},
    {"global_avg_pool", {"SetPool::pool_planar"}},
    {"instance_norm", {"BatchNormPerImage::enqueue"}},
    {"group_norm", {"BatchNormPerImage::enqueue"}},
    {"pad2d", {"Pad2d::enqueue"}},
    {"resize_bilinear", {"ResizeBilinear::enqueue"}},
};

}  // namespace

TEST_CASE("op harness: GEMM, PackB and Dense, every knob set", "[op_harness]") {
    run_rows({"Gemm::", "PackB::", "Dense::"}, false);
}

TEST_CASE("op harness: convolutions, both paths", "[op_harness]") {
    run_rows({"Conv2d::", "ConvTranspose2d::"}, false);
}

TEST_CASE("op harness: batch norm and elementwise ops", "[op_harness]") {
    run_rows({"BatchNormPerImage::", "Elementwise::"}, false);
}

TEST_CASE("op harness: MLPs and the frequency encoding", "[op_harness]") {
    run_rows({"FusedMlp::", "DenseMlp::", "FrequencyEncodePlanar::"}, false);
}

TEST_CASE("op harness: JBU, SH, set pooling, image gathering", "[op_harness]") {
    run_rows({"JointBilateralUpsample::", "ShEvaluate::", "SetPool::", "GatherImage::"}, false);
}

TEST_CASE("op harness: max pooling", "[op_harness]") {
    run_rows({"MaxPool2d::"}, false);
}

TEST_CASE("op harness: padding and bilinear resize", "[op_harness]") {
    run_rows({"Pad2d::", "ResizeBilinear::"}, false);
}

TEST_CASE("op harness: probe shading and the light-transition function", "[op_harness]") {
    run_rows({"ProbeShade::", "VoxelLtf::"}, false);
}

TEST_CASE("op harness: the tiny case of every op (the oclgrind subset)", "[op_harness][oclgrind]") {
    run_rows({}, true);
}

TEST_CASE("op harness: every public entry point of host/src/ops/ and every graph node kind has rows, a tiny one "
          "among them", "[op_harness]") {
    // What must be covered comes from the library, not from a list kept beside the table: the entry points declared
    // in host/src/ops/*.hpp (scanned) and the node kinds of graph/node_kind.hpp. A new op, or a new kind, fails here
    // by name until the table has its rows.
    const std::map<std::string, std::string> declared = declared_entry_points();
    REQUIRE(declared.size() >= 20);  // the scan found the ops (a broken scan must not pass with nothing to cover)
    std::map<std::string, int> rows, tiny;
    for (const OpCase& c : op_cases()) {
        CHECK(c.tolerance >= 0.0);
        for (const std::string& e : entry_points_of_row(c.op)) {
            INFO("the table's row '" << c.id() << "' names " << e);
            CHECK(declared.count(e) == 1);  // no row for an entry point the headers do not declare
            ++rows[e];
            if (c.tiny) ++tiny[e];
        }
    }
    for (const auto& [e, header] : declared) {
        INFO(e << " (host/src/ops/" << header << ")");
        if (const auto via = kReachedThrough.find(e); via != kReachedThrough.end()) {
            // Covered through the entry points whose implementation it is: rows of theirs whose name says so.
            for (const std::string& owner : via->second.owners) {
                INFO("reached through " << owner << ", rows named '" << via->second.rows << "'");
                int n = 0;
                for (const OpCase& c : op_cases()) n += c.op == owner && c.name.find(via->second.rows) != std::string::npos;
                CHECK(n > 0);
            }
            CHECK(rows.count(e) == 0);
            continue;
        }
        CHECK(rows[e] > 0);  // "<entry point> (host/src/ops/<header>)": the op has no row in op_cases.cpp
        CHECK(tiny[e] > 0);  // ... and no tiny row (the oclgrind subset)
    }
    for (const auto& [e, why] : kReachedThrough) {
        INFO("kReachedThrough names " << e);
        CHECK(declared.count(e) == 1);  // not stale
    }

    // Every node kind a model file can name runs on entry points that have rows (concat on none: the planner places
    // its inputs side by side).
    for (std::string_view kind : detail::kNodeKindNames) {
        INFO("node kind '" << kind << "' (graph/node_kind.hpp)");
        const auto it = kNodeKindOps.find(kind);
        REQUIRE(it != kNodeKindOps.end());  // a new kind: name the entry points its node adapter enqueues
        for (const char* e : it->second) {
            INFO(e);
            CHECK(declared.count(e) == 1);
            CHECK(rows[e] > 0);
        }
    }
    CHECK(kNodeKindOps.size() == detail::kNodeKinds);  // no kind that is gone

    CHECK(gemm_variants() == test::gpu_and_cpu_gemm_variants());
    // Every knob set has its row.
    for (const detail::GemmParams& p : gemm_variants()) {
        bool found = false;
        for (const OpCase& c : op_cases()) found |= c.op == "Gemm::enqueue" && c.name == "knobs " + p.to_string();
        CHECK(found);
    }
}

TEST_CASE("op harness: the entry-point scan finds public, non-const members taking the context, and nothing else",
          "[op_harness]") {
    const std::string header = R"(
        // class Commented { public: void enqueue(Context& ctx); };
        struct Forward;
        class Op {
        public:
            explicit Op(Context& ctx);  // a constructor
            void enqueue(Context& ctx, const View& x,
                         const View& y);
            static bool fits_device(Context& ctx, int n);
            int count(Context& ctx) const;
            enum class Form { a, b };
            cl_event run(Context& ctx, Form f = Form::a) { return helper(ctx, "}{"); }
        private:
            struct Inner { void enqueue(Context& ctx); };
            void helper(Context& ctx);
        };
        struct Plain {
            void pool(Context& ctx);
        protected:
            void hidden(Context& ctx);
        };
        inline void free_function(Context& ctx);
    )";
    CHECK(entry_points_in(header) == std::vector<std::string>{"Op::enqueue", "Op::run", "Plain::pool"});
    CHECK(entry_points_of_row("Elementwise::sanitize + sanitized_count") ==
          std::vector<std::string>{"Elementwise::sanitize", "Elementwise::sanitized_count"});
}

TEST_CASE("op harness: the guard check reports a damaged guard, a written input and an op's wrong offset",
          "[op_harness][oclgrind]") {
    auto& ctx = test::ctx();
    const std::vector<float> payload = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f};
    const float one = 1.0f;
    SECTION("a word written just before the payload") {
        GuardedBuffer b(ctx, "x", Role::Output, payload.size(), nullptr);
        CHECK(b.check(ctx, "case").empty());
        detail::check(clEnqueueWriteBuffer(ctx.queue(), b.mem(), CL_TRUE, b.offset_bytes() - 4, 4, &one, 0, nullptr,
                                           nullptr),
                      "test", "clEnqueueWriteBuffer");
        CHECK_THAT(b.check(ctx, "case"), Catch::Contains("case: buffer 'x'") &&
                                             Catch::Contains("guard before the payload") &&
                                             Catch::Contains("first damaged word 0") && Catch::Contains("0x3f800000"));
    }
    SECTION("a word written three past the end") {
        GuardedBuffer b(ctx, "y", Role::Scratch, payload.size(), nullptr);
        detail::check(clEnqueueWriteBuffer(ctx.queue(), b.mem(), CL_TRUE, b.offset_bytes() + (payload.size() + 3) * 4,
                                           4, &one, 0, nullptr, nullptr),
                      "test", "clEnqueueWriteBuffer");
        CHECK_THAT(b.check(ctx, "case"),
                   Catch::Contains("guard after the payload") && Catch::Contains("first damaged word 3"));
    }
    SECTION("an input's payload changed") {
        GuardedBuffer b(ctx, "w", Role::Input, payload.size(), payload.data());
        CHECK(b.check(ctx, "case").empty());
        detail::check(clEnqueueWriteBuffer(ctx.queue(), b.mem(), CL_TRUE, b.offset_bytes() + 8, 4, &one, 0, nullptr,
                                           nullptr),
                      "test", "clEnqueueWriteBuffer");
        CHECK_THAT(b.check(ctx, "case"), Catch::Contains("an input the op wrote: payload word 2"));
        // The same write into an in-out buffer is the op's business.
        GuardedBuffer io(ctx, "io", Role::InOut, payload.size(), payload.data());
        detail::check(clEnqueueWriteBuffer(ctx.queue(), io.mem(), CL_TRUE, io.offset_bytes() + 8, 4, &one, 0, nullptr,
                                           nullptr),
                      "test", "clEnqueueWriteBuffer");
        CHECK(io.check(ctx, "case").empty());
    }
    SECTION("an op given an offset one element too far writes into the guard after") {
        detail::Elementwise ew(ctx);
        GuardedBuffer x(ctx, "x", Role::InOut, payload.size(), payload.data());
        GuardedBuffer y(ctx, "y", Role::Input, payload.size(), payload.data());
        const int n = int(payload.size());
        ew.add(ctx, detail::View{x.mem(), x.offset() + 1, {1, 1, n}}, detail::View{y.mem(), y.offset(), {1, 1, n}});
        ctx.finish();
        CHECK_THAT(x.check(ctx, "add, off by one"),
                   Catch::Contains("'x', guard after the payload, first damaged word 0"));
        CHECK(y.check(ctx, "add, off by one").empty());
    }
}
