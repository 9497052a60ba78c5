// The C ABI's registry of live handles (bindings/c/c_handles.cpp; ctest c_handles), compiled into this test with its
// handle values starting 8 before the end of their range, so that the end is reached: values distinct, never NULL and
// never given out twice; creating a handle once all are given out is refused with NGI_ERROR_OUT_OF_MEMORY (before,
// the counter wrapped to 0 and handed out NULL, then the first values again), and so is every later one; an object
// whose registration fails (no value left, or the table cannot grow: std::bad_alloc) is deleted, not leaked; the
// checks before every use and their messages (a released handle, another type's handle, NULL, a refused release that
// releases nothing, the last release deleting the object).
#include <cstdint>
#define NGI_C_FIRST_HANDLE (UINTPTR_MAX - 127)  // 8 values: ...f90, ...fa0, ..., ...ff0 (the last multiple of 16)
#include "c_handles.cpp"

#include <cstdio>
#include <cstdlib>
#include <new>
#include <set>
#include <vector>

namespace {

int g_failures = 0;
#define CHECK(cond)                                                                     \
    do {                                                                                \
        if (!(cond)) {                                                                  \
            std::fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond); \
            ++g_failures;                                                               \
        }                                                                               \
    } while (0)

bool g_fail_next_new = false;  // the next operator new throws std::bad_alloc
int g_destroyed = 0;           // test objects deleted so far

struct test_frame : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Frame;
    ~test_frame() override { ++g_destroyed; }
};
struct test_model : ngi_handle {
    static constexpr HandleKind kKind = HandleKind::Model;
    ~test_model() override { ++g_destroyed; }
};

// The ApiError f() throws ({NGI_OK, ""} when it throws none).
template <class F>
c_abi::ApiError api_error(F&& f) {
    try {
        f();
    } catch (const c_abi::ApiError& e) {
        return e;
    }
    return {NGI_OK, ""};
}

}  // namespace

void* operator new(std::size_t n) {
    if (g_fail_next_new) {
        g_fail_next_new = false;
        throw std::bad_alloc();
    }
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

int main() {
    using namespace c_abi;
    const std::uintptr_t first = NGI_C_FIRST_HANDLE, last = UINTPTR_MAX - 15;

    // The table cannot grow: the object is deleted with what it holds, nothing is registered, no value is used up.
    {
        auto object = std::make_unique<test_frame>();
        g_fail_next_new = true;
        bool threw = false;
        try {
            track(std::move(object));
        } catch (const std::bad_alloc&) {
            threw = true;
        }
        CHECK(threw);
        CHECK(!g_fail_next_new);
        CHECK(g_destroyed == 1);
        CHECK(api_error([&] { live(reinterpret_cast<const test_frame*>(first), "frame"); }).status ==
              NGI_ERROR_INVALID_HANDLE);
    }

    // Every value once, in order, multiples of 16, never NULL.
    std::vector<test_frame*> frames;
    for (int i = 0; i < 8; ++i) frames.push_back(track(std::make_unique<test_frame>()));
    std::set<std::uintptr_t> values;
    for (test_frame* h : frames) values.insert(reinterpret_cast<std::uintptr_t>(h));
    CHECK(values.size() == 8);
    CHECK(*values.begin() == first && *values.rbegin() == last);
    CHECK(reinterpret_cast<std::uintptr_t>(frames.front()) == first);
    CHECK(reinterpret_cast<std::uintptr_t>(frames.back()) == last);
    for (std::uintptr_t v : values) CHECK(v != 0 && v % 16 == 0);

    // All given out: refused (not NULL, not a value again), the object deleted; a release gives no value back.
    const std::string bits = std::to_string(sizeof(void*) * 8 - 4);
    for (int attempt = 0; attempt < 2; ++attempt) {
        const int destroyed = g_destroyed;
        const ApiError e = api_error([] { track(std::make_unique<test_model>()); });
        CHECK(e.status == NGI_ERROR_OUT_OF_MEMORY);
        CHECK(e.message == "no handle left: this process has been given all 2^" + bits +
                               " handle values, and a value is never given out twice");
        CHECK(g_destroyed == destroyed + 1);
        if (attempt == 0) {
            release_handle(frames[0], "frame");
            CHECK(g_destroyed == destroyed + 2);
        }
    }

    // The checks and their messages, as every entry point reports them.
    CHECK(&live(frames[1], "frame") == static_cast<test_frame*>(find_handle(frames[1], HandleKind::Frame, "frame")));
    ApiError e = api_error([&] { live(frames[0], "frame"); });
    CHECK(e.status == NGI_ERROR_INVALID_HANDLE &&
          e.message == "frame is not a live handle (released, or never created)");
    e = api_error([&] { live(reinterpret_cast<const test_model*>(frames[1]), "model"); });
    CHECK(e.status == NGI_ERROR_INVALID_ARGUMENT && e.message == "model is an ngi_frame handle, not an ngi_model");
    e = api_error([] { live(static_cast<const test_frame*>(nullptr), "frame"); });
    CHECK(e.status == NGI_ERROR_INVALID_HANDLE && e.message == "frame is NULL");
    e = api_error([] { retain_handle(static_cast<test_frame*>(nullptr), "frame"); });
    CHECK(e.status == NGI_ERROR_INVALID_HANDLE && e.message == "frame is NULL");
    e = api_error([&] { retain_handle(frames[0], "frame"); });
    CHECK(e.status == NGI_ERROR_INVALID_HANDLE);

    // References: retained once, the object outlives one release and goes with the last; a third is refused.
    int destroyed = g_destroyed;
    retain_handle(frames[2], "frame");
    release_handle(frames[2], "frame");
    CHECK(g_destroyed == destroyed);
    release_handle(frames[2], "frame");
    CHECK(g_destroyed == destroyed + 1);
    e = api_error([&] { release_handle(frames[2], "frame"); });
    CHECK(e.status == NGI_ERROR_INVALID_HANDLE && g_destroyed == destroyed + 1);

    // A release through another type is refused and releases nothing; NULL is like free(NULL).
    e = api_error([&] { release_handle(reinterpret_cast<test_model*>(frames[3]), "model"); });
    CHECK(e.status == NGI_ERROR_INVALID_ARGUMENT && e.message == "model is an ngi_frame handle, not an ngi_model");
    CHECK(api_error([&] { live(frames[3], "frame"); }).status == NGI_OK);
    release_handle(static_cast<test_frame*>(nullptr), "frame");

    destroyed = g_destroyed;
    for (int i = 3; i < 8; ++i) release_handle(frames[i], "frame");
    CHECK(g_destroyed == destroyed + 5);
    CHECK(api_error([&] { live(frames[1], "frame"); }).status == NGI_OK);
    release_handle(frames[1], "frame");

    if (g_failures) {
        std::fprintf(stderr, "c_handles: %d checks failed\n", g_failures);
        return 1;
    }
    std::printf("c_handles: values unique and never reused, exhaustion refused, failed registrations leak nothing, "
                "the checks' messages\n");
    return 0;
}
