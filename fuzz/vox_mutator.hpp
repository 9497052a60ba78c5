// A structure-aware mutator for fuzz_vox: it edits a MagicaVoxel file at the level of its chunks (SIZE/XYZI
// pairs, RGBA, MATL, the scene graph nTRN/nGRP/nSHP, skipped chunks) and writes the file back with every chunk
// size recomputed, so that a mutant is still a well-formed .vox most of the time. Byte mutations alone mostly break
// the chunk structure or the voxel coordinates and stop in the parser: few of their inputs become a scene the
// renderer's host-side preparation (the camera path) sees. Inputs that do not parse as a chunk list, and a share
// of the rest, get libFuzzer's byte mutations instead (LLVMFuzzerMutate), so the parser's error paths stay covered.
#pragma once
#include <algorithm>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

namespace ngi::fuzz::vox {

using Rng = std::minstd_rand;
using Dict = std::vector<std::pair<std::string, std::string>>;

struct Chunk {
    std::string id;       // 4 characters
    std::string content;  // raw content bytes
    std::string children; // raw children bytes (only MAIN's are parsed; nested children are kept as they are)
};

struct File {
    std::int32_t version = 150;
    std::string main_content;
    std::vector<Chunk> chunks;  // MAIN's children
    std::string trailer;        // bytes after MAIN (kept)
};

inline void put_i32(std::string& s, std::int32_t v) {
    const auto u = std::uint32_t(v);
    for (int k = 0; k < 4; ++k) s += char((u >> (8 * k)) & 0xff);
}

// A little-endian reader that reports failure instead of throwing (the mutator must not throw).
struct Cursor {
    const std::string* s;
    std::size_t pos = 0, end = 0;
    bool ok = true;
    std::int32_t i32() {
        if (end - pos < 4) { ok = false; return 0; }
        const auto* p = reinterpret_cast<const unsigned char*>(s->data() + pos);
        pos += 4;
        return std::int32_t(std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
                            std::uint32_t(p[3]) << 24);
    }
    std::string bytes(std::size_t n) {
        if (end - pos < n) { ok = false; return {}; }
        std::string r = s->substr(pos, n);
        pos += n;
        return r;
    }
    std::string str() {
        const std::int32_t n = i32();
        if (!ok || n < 0) { ok = false; return {}; }
        return bytes(std::size_t(n));
    }
    Dict dict() {
        const std::int32_t n = i32();
        Dict d;
        if (!ok || n < 0 || std::size_t(n) > (end - pos) / 8) { ok = false; return d; }
        for (int i = 0; i < n && ok; ++i) {
            std::string k = str();
            std::string v = str();
            d.emplace_back(std::move(k), std::move(v));
        }
        return d;
    }
};

inline void put_str(std::string& s, const std::string& v) {
    put_i32(s, std::int32_t(v.size()));
    s += v;
}
inline void put_dict(std::string& s, const Dict& d) {
    put_i32(s, std::int32_t(d.size()));
    for (const auto& [k, v] : d) put_str(s, k), put_str(s, v);
}

// The chunk list of a .vox file. With `repair`, sizes that do not fit are not a failure: MAIN takes the rest of the
// file and the child list ends at the first chunk that does not fit (a byte mutant becomes well-formed again when
// written back); without it, such a file is not a chunk list (nullopt).
inline std::optional<File> parse(const std::uint8_t* data, std::size_t size, bool repair = false) {
    const std::string b(reinterpret_cast<const char*>(data), size);
    if (size < 20 || b.compare(0, 4, "VOX ") != 0) return std::nullopt;
    Cursor c{&b, 4, size};
    File f;
    f.version = c.i32();
    if (c.bytes(4) != "MAIN") return std::nullopt;
    std::int32_t n = c.i32(), m = c.i32();
    if (!c.ok || n < 0 || m < 0 || std::size_t(n) > c.end - c.pos || std::size_t(m) > c.end - c.pos - std::size_t(n)) {
        if (!repair || !c.ok) return std::nullopt;
        n = 0;
        m = std::int32_t(c.end - c.pos);
    }
    f.main_content = c.bytes(std::size_t(n));
    Cursor k{&b, c.pos, c.pos + std::size_t(m)};
    f.trailer = b.substr(c.pos + std::size_t(m));
    while (k.pos < k.end) {
        Chunk ch;
        ch.id = k.bytes(4);
        const std::int32_t cn = k.i32(), cm = k.i32();
        if (!k.ok || cn < 0 || cm < 0 || std::size_t(cn) > k.end - k.pos ||
            std::size_t(cm) > k.end - k.pos - std::size_t(cn)) {
            if (repair) break;
            return std::nullopt;
        }
        ch.content = k.bytes(std::size_t(cn));
        ch.children = k.bytes(std::size_t(cm));
        f.chunks.push_back(std::move(ch));
    }
    return f;
}

inline std::string serialize(const File& f) {
    std::string kids;
    for (const Chunk& c : f.chunks) {
        kids += c.id.substr(0, 4) + std::string(4 - std::min<std::size_t>(4, c.id.size()), ' ');
        put_i32(kids, std::int32_t(c.content.size()));
        put_i32(kids, std::int32_t(c.children.size()));
        kids += c.content + c.children;
    }
    std::string out = "VOX ";
    put_i32(out, f.version);
    out += "MAIN";
    put_i32(out, std::int32_t(f.main_content.size()));
    put_i32(out, std::int32_t(kids.size()));
    return out + f.main_content + kids + f.trailer;
}

// The scene-graph chunks, parsed so that their fields can be edited one by one.
struct Trn { std::int32_t id = 0; Dict attrs; std::int32_t child = 0, reserved = -1, layer = 0; std::vector<Dict> frames; std::int32_t declared_frames = 1; };
struct Grp { std::int32_t id = 0; Dict attrs; std::vector<std::int32_t> kids; };
struct Shp { std::int32_t id = 0; Dict attrs; std::vector<std::pair<std::int32_t, Dict>> models; };
struct Matl { std::int32_t id = 0; Dict props; };

inline std::optional<Trn> parse_trn(const std::string& s) {
    Cursor c{&s, 0, s.size()};
    Trn t;
    t.id = c.i32();
    t.attrs = c.dict();
    t.child = c.i32();
    t.reserved = c.i32();
    t.layer = c.i32();
    t.declared_frames = c.i32();
    for (int i = 0; c.ok && i < t.declared_frames && c.pos < c.end; ++i) t.frames.push_back(c.dict());
    if (!c.ok) return std::nullopt;
    return t;
}
inline std::string write_trn(const Trn& t) {
    std::string s;
    put_i32(s, t.id);
    put_dict(s, t.attrs);
    put_i32(s, t.child);
    put_i32(s, t.reserved);
    put_i32(s, t.layer);
    put_i32(s, t.declared_frames);
    for (const Dict& d : t.frames) put_dict(s, d);
    return s;
}
inline std::optional<Grp> parse_grp(const std::string& s) {
    Cursor c{&s, 0, s.size()};
    Grp g;
    g.id = c.i32();
    g.attrs = c.dict();
    const std::int32_t n = c.i32();
    if (!c.ok || n < 0 || std::size_t(n) > (c.end - c.pos) / 4) return std::nullopt;
    for (int i = 0; i < n; ++i) g.kids.push_back(c.i32());
    return g;
}
inline std::string write_grp(const Grp& g) {
    std::string s;
    put_i32(s, g.id);
    put_dict(s, g.attrs);
    put_i32(s, std::int32_t(g.kids.size()));
    for (std::int32_t k : g.kids) put_i32(s, k);
    return s;
}
inline std::optional<Shp> parse_shp(const std::string& s) {
    Cursor c{&s, 0, s.size()};
    Shp h;
    h.id = c.i32();
    h.attrs = c.dict();
    const std::int32_t n = c.i32();
    if (!c.ok || n < 0 || std::size_t(n) > (c.end - c.pos) / 8) return std::nullopt;
    for (int i = 0; i < n && c.ok; ++i) {
        const std::int32_t m = c.i32();
        h.models.emplace_back(m, c.dict());
    }
    if (!c.ok) return std::nullopt;
    return h;
}
inline std::string write_shp(const Shp& h) {
    std::string s;
    put_i32(s, h.id);
    put_dict(s, h.attrs);
    put_i32(s, std::int32_t(h.models.size()));
    for (const auto& [m, d] : h.models) put_i32(s, m), put_dict(s, d);
    return s;
}
inline std::optional<Matl> parse_matl(const std::string& s) {
    Cursor c{&s, 0, s.size()};
    Matl m;
    m.id = c.i32();
    m.props = c.dict();
    if (!c.ok) return std::nullopt;
    return m;
}
inline std::string write_matl(const Matl& m) {
    std::string s;
    put_i32(s, m.id);
    put_dict(s, m.props);
    return s;
}

inline std::string size_content(int x, int y, int z) {
    std::string s;
    put_i32(s, x), put_i32(s, y), put_i32(s, z);
    return s;
}

template <class T>
const T& pick(Rng& r, const std::vector<T>& v) {
    return v[std::uniform_int_distribution<std::size_t>(0, v.size() - 1)(r)];
}
inline int uniform(Rng& r, int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(r); }

// Sets key `k` of `d` (replacing an existing entry), or removes it when `value` is empty and `remove` is true.
inline void set_key(Dict& d, const std::string& k, const std::string& v) {
    for (auto& e : d)
        if (e.first == k) { e.second = v; return; }
    d.emplace_back(k, v);
}

// Numbers around the loader's limits: translation caps (+-2^20), float extremes for MATL values, non-numbers.
inline std::string interesting_number(Rng& r) {
    static const std::vector<std::string> v = {"0", "1", "-1", "0.5", "4", "5", "100", "1e-45", "1e-38", "3e38",
                                               "3.4028235e38", "1e39", "-3e38", "nan", "inf", "-inf", "", "x", "1 2",
                                               "65504", "1e5", "2147483647", "-2147483648", "0x10", " 1"};
    return pick(r, v);
}
inline std::string translation(Rng& r) {
    static const std::vector<int> big = {0, 1, -1, 255, 256, 1 << 20, (1 << 20) + 1, -(1 << 20), 4096, 2047};
    auto one = [&] { return std::to_string(uniform(r, 0, 3) == 0 ? pick(r, big) : uniform(r, -40, 40)); };
    switch (uniform(r, 0, 9)) {
        case 0: return interesting_number(r);
        case 1: return one() + " " + one();
        case 2: return one() + "  " + one() + " " + one() + " ";
        default: return one() + " " + one() + " " + one();
    }
}

// The model size (SIZE) that governs the XYZI chunk at `xyzi`: the nearest SIZE before it.
inline std::optional<std::size_t> size_before(const File& f, std::size_t xyzi) {
    for (std::size_t i = xyzi; i-- > 0;)
        if (f.chunks[i].id == "SIZE") return i;
    return std::nullopt;
}

inline std::vector<std::size_t> chunks_of(const File& f, const char* id) {
    std::vector<std::size_t> v;
    for (std::size_t i = 0; i < f.chunks.size(); ++i)
        if (f.chunks[i].id == id) v.push_back(i);
    return v;
}

inline std::vector<std::int32_t> node_ids(const File& f) {
    std::vector<std::int32_t> ids;
    for (const Chunk& c : f.chunks)
        if ((c.id == "nTRN" || c.id == "nGRP" || c.id == "nSHP") && c.content.size() >= 4) {
            Cursor k{&c.content, 0, c.content.size()};
            ids.push_back(k.i32());
        }
    return ids;
}

inline void mutate_xyzi(File& f, std::size_t at, Rng& r) {
    Chunk& c = f.chunks[at];
    if (c.content.size() < 4) c.content = std::string(4, '\0');
    std::string vox = c.content.substr(4);
    vox.resize(vox.size() / 4 * 4);
    int sx = 8, sy = 8, sz = 8;
    if (auto s = size_before(f, at); s && f.chunks[*s].content.size() >= 12) {
        Cursor k{&f.chunks[*s].content, 0, 12};
        sx = k.i32(), sy = k.i32(), sz = k.i32();
    }
    // Coordinates inside the model (usually), sometimes on or past its edge.
    auto coord = [&](int n) {
        if (uniform(r, 0, 15) == 0) return std::uint8_t(uniform(r, 0, 255));
        return std::uint8_t(uniform(r, 0, std::clamp(n, 1, 256) - 1));
    };
    const std::size_t count = vox.size() / 4;
    switch (uniform(r, 0, 5)) {
        case 0:  // add voxels
        case 1: {
            const int add = uniform(r, 0, 3) == 0 ? uniform(r, 1, 64) : 1;
            for (int i = 0; i < add; ++i)
                vox += std::string{char(coord(sx)), char(coord(sy)), char(coord(sz)), char(uniform(r, 0, 255))};
            break;
        }
        case 2:  // move one
            if (count) {
                const std::size_t i = std::size_t(uniform(r, 0, int(count) - 1));
                vox[4 * i + std::size_t(uniform(r, 0, 2))] = char(coord(uniform(r, 0, 1) ? sx : sz));
            }
            break;
        case 3:  // delete some
            if (count) {
                const std::size_t i = std::size_t(uniform(r, 0, int(count) - 1));
                const std::size_t n = std::min<std::size_t>(count - i, std::size_t(uniform(r, 1, 4)));
                vox.erase(4 * i, 4 * n);
            }
            break;
        case 4:  // recolour one (0 = no colour: the loader skips it)
            if (count) vox[4 * std::size_t(uniform(r, 0, int(count) - 1)) + 3] = char(uniform(r, 0, 255));
            break;
        default: {  // fill the model box (a solid block of the model's size, capped)
            const int n = std::clamp(sx, 1, 16), m = std::clamp(sy, 1, 16), o = std::clamp(sz, 1, 16);
            const char colour = char(uniform(r, 1, 255));
            vox.clear();
            for (int z = 0; z < o; ++z)
                for (int y = 0; y < m; ++y)
                    for (int x = 0; x < n; ++x)
                        if (uniform(r, 0, 3)) vox += std::string{char(x), char(y), char(z), colour};
            break;
        }
    }
    std::string content;
    // The declared count: usually the true one, sometimes off by a few (the loader's truncation check).
    const std::int32_t declared = std::int32_t(vox.size() / 4) + (uniform(r, 0, 15) == 0 ? uniform(r, -2, 2) : 0);
    put_i32(content, declared);
    c.content = content + vox;
}

inline void mutate_size(Chunk& c, Rng& r) {
    int d[3] = {1, 1, 1};
    if (c.content.size() >= 12) {
        Cursor k{&c.content, 0, 12};
        d[0] = k.i32(), d[1] = k.i32(), d[2] = k.i32();
    }
    static const std::vector<int> extreme = {0, -1, 1, 2, 255, 256, 257, 1 << 16, INT32_MAX, INT32_MIN};
    const int axis = uniform(r, 0, 2);
    switch (uniform(r, 0, 7)) {
        case 0: d[axis] = pick(r, extreme); break;
        case 1: d[axis] = int(std::clamp<std::int64_t>(std::int64_t(d[axis]) + uniform(r, -3, 3), 1, 256)); break;
        default: d[axis] = uniform(r, 1, 64); break;
    }
    c.content = size_content(d[0], d[1], d[2]);
}

// Drops the voxels of the XYZI chunk after SIZE chunk `at` that lie outside that size (after a SIZE edit shrank it:
// else nearly every shrink is refused as "voxel outside its model").
inline void clip_xyzi(File& f, std::size_t at) {
    if (at + 1 >= f.chunks.size() || f.chunks[at + 1].id != "XYZI" || f.chunks[at].content.size() < 12) return;
    Cursor k{&f.chunks[at].content, 0, 12};
    const int sx = k.i32(), sy = k.i32(), sz = k.i32();
    Chunk& x = f.chunks[at + 1];
    if (x.content.size() < 4) return;
    std::string kept;
    for (std::size_t i = 4; i + 4 <= x.content.size(); i += 4) {
        const auto* v = reinterpret_cast<const unsigned char*>(x.content.data() + i);
        if (v[0] < sx && v[1] < sy && v[2] < sz) kept.append(x.content, i, 4);
    }
    x.content.clear();
    put_i32(x.content, std::int32_t(kept.size() / 4));
    x.content += kept;
}

inline void mutate_rgba(Chunk& c, Rng& r) {
    if (c.content.size() < 1024) c.content.resize(1024, char(0xff));
    const std::size_t i = std::size_t(uniform(r, 0, 255));
    static const std::vector<std::uint32_t> colours = {0x00000000u, 0xffffffffu, 0xff0000ffu, 0x00ff00ffu, 0x0000ffffu};
    const std::uint32_t v = uniform(r, 0, 1) ? pick(r, colours) : std::uint32_t(r());
    for (int k = 0; k < 4; ++k) c.content[4 * i + std::size_t(k)] = char((v >> (8 * k)) & 0xff);
    if (uniform(r, 0, 31) == 0) c.content.resize(std::size_t(uniform(r, 0, 1023)));  // truncated palette
}

inline void mutate_matl(Chunk& c, Rng& r) {
    Matl m = parse_matl(c.content).value_or(Matl{1, {}});
    static const std::vector<std::string> keys = {"_type", "_emit", "_flux", "_rough", "_ior", "_spec", "_metal",
                                                  "_weight", "_ldr", "_trans", "_alpha", "_d", "_media", "_g"};
    static const std::vector<std::string> types = {"_emit", "_diffuse", "_metal", "_glass", "_blend", "_media", "", "_EMIT"};
    switch (uniform(r, 0, 5)) {
        case 0: m.id = uniform(r, 0, 3) == 0 ? pick(r, std::vector<int>{0, 255, 256, -1, INT32_MAX}) : uniform(r, 1, 255); break;
        case 1: set_key(m.props, "_type", pick(r, types)); break;
        case 2:
            if (!m.props.empty()) m.props.erase(m.props.begin() + uniform(r, 0, int(m.props.size()) - 1));
            break;
        case 3: set_key(m.props, "_type", "_emit"); set_key(m.props, "_emit", interesting_number(r)); break;
        default: set_key(m.props, pick(r, keys), interesting_number(r)); break;
    }
    c.content = write_matl(m);
}

inline void mutate_trn(Chunk& c, const File& f, Rng& r) {
    auto t = parse_trn(c.content);
    if (!t) { t = Trn{}; t->frames.push_back({}); }
    const std::vector<std::int32_t> ids = node_ids(f);
    switch (uniform(r, 0, 7)) {
        case 0:
        case 1:
        case 2:
            if (t->frames.empty()) t->frames.push_back({});
            set_key(t->frames[0], "_t", translation(r));
            break;
        case 3: {  // _r: a valid rotation byte mostly, anything sometimes
            if (t->frames.empty()) t->frames.push_back({});
            static const std::vector<int> valid = {4, 6, 8, 9, 17, 20, 24, 40, 98, 120};
            set_key(t->frames[0], "_r", uniform(r, 0, 3) ? std::to_string(pick(r, valid)) : interesting_number(r));
            break;
        }
        case 4: {  // frame count: frames added or removed, or a count the chunk cannot hold
            const int mode = uniform(r, 0, 6) == 0 ? 3 : uniform(r, 0, 2);
            if (mode == 0) t->frames.push_back({{"_t", translation(r)}, {"_f", std::to_string(t->frames.size())}});
            else if (mode == 1 && t->frames.size() > 1) t->frames.pop_back();
            else if (mode == 2) t->frames.clear();
            if (mode == 3) {
                t->declared_frames = pick(r, std::vector<int>{0, -1, 2, 1000, INT32_MAX});
                c.content = write_trn(*t);
                return;
            }
            break;
        }
        case 5: t->child = ids.empty() || uniform(r, 0, 7) == 0 ? uniform(r, -1, 8) : pick(r, ids); break;
        case 6: t->id = uniform(r, 0, 7) == 0 ? uniform(r, -1, 64) : (ids.empty() ? 0 : pick(r, ids)); break;
        default: set_key(t->attrs, uniform(r, 0, 1) ? "_name" : "_hidden", interesting_number(r)); break;
    }
    t->declared_frames = std::int32_t(t->frames.size());  // consistent unless the edit above was the count
    c.content = write_trn(*t);
}

inline void mutate_grp(Chunk& c, const File& f, Rng& r) {
    auto g = parse_grp(c.content).value_or(Grp{});
    const std::vector<std::int32_t> ids = node_ids(f);
    auto some_id = [&] { return ids.empty() || uniform(r, 0, 7) == 0 ? uniform(r, -1, 16) : pick(r, ids); };
    switch (uniform(r, 0, 4)) {
        case 0: g.kids.push_back(some_id()); break;
        case 1:
            if (!g.kids.empty()) g.kids.erase(g.kids.begin() + uniform(r, 0, int(g.kids.size()) - 1));
            break;
        case 2:  // a child listed twice (shared subtrees: the walk's visit cap)
            if (!g.kids.empty()) g.kids.push_back(pick(r, g.kids));
            break;
        case 3:
            if (!g.kids.empty()) g.kids[std::size_t(uniform(r, 0, int(g.kids.size()) - 1))] = some_id();
            break;
        default: g.id = some_id(); break;
    }
    c.content = write_grp(g);
}

inline void mutate_shp(Chunk& c, const File& f, Rng& r) {
    auto h = parse_shp(c.content).value_or(Shp{});
    const int models = int(chunks_of(f, "SIZE").size());
    auto some_model = [&] { return uniform(r, 0, 7) == 0 ? uniform(r, -1, models + 2) : uniform(r, 0, std::max(0, models - 1)); };
    switch (uniform(r, 0, 3)) {
        case 0: h.models.emplace_back(some_model(), Dict{}); break;
        case 1:
            if (!h.models.empty()) h.models.erase(h.models.begin() + uniform(r, 0, int(h.models.size()) - 1));
            break;
        case 2:
            if (!h.models.empty()) h.models[std::size_t(uniform(r, 0, int(h.models.size()) - 1))].first = some_model();
            break;
        default: {
            const std::vector<std::int32_t> ids = node_ids(f);
            h.id = ids.empty() ? uniform(r, 0, 8) : pick(r, ids);
            break;
        }
    }
    c.content = write_shp(h);
}

// A new chunk: a model (SIZE + XYZI), a placed model (nTRN -> nSHP), a material, a skipped chunk.
inline void add_chunk(File& f, Rng& r) {
    const std::size_t at = f.chunks.empty() ? 0 : std::size_t(uniform(r, 0, int(f.chunks.size())));
    std::vector<Chunk> add;
    switch (uniform(r, 0, 4)) {
        case 0: {
            const int x = uniform(r, 1, 12), y = uniform(r, 1, 12), z = uniform(r, 1, 12);
            add.push_back({"SIZE", size_content(x, y, z), {}});
            add.push_back({"XYZI", std::string(4, '\0'), {}});
            break;
        }
        case 1: {
            const std::vector<std::int32_t> ids = node_ids(f);
            std::int32_t next = 0;  // a fresh id (ids near INT32_MAX: wrap to small ones rather than overflow)
            for (std::int32_t i : ids) next = std::max(next, i < INT32_MAX - 2 ? i + 1 : 0);
            Trn t;
            t.id = next;
            t.child = next + 1;
            t.frames.push_back({{"_t", translation(r)}});
            t.declared_frames = 1;
            Shp h;
            h.id = next + 1;
            h.models.emplace_back(uniform(r, 0, std::max(0, int(chunks_of(f, "SIZE").size()) - 1)), Dict{});
            add.push_back({"nTRN", write_trn(t), {}});
            add.push_back({"nSHP", write_shp(h), {}});
            // Hook it into a group so the walk reaches it.
            for (std::size_t g : chunks_of(f, "nGRP"))
                if (auto grp = parse_grp(f.chunks[g].content)) {
                    grp->kids.push_back(next);
                    f.chunks[g].content = write_grp(*grp);
                    break;
                }
            break;
        }
        case 2: {
            Matl m{uniform(r, 1, 255), {{"_type", "_emit"}, {"_emit", interesting_number(r)}}};
            if (uniform(r, 0, 1)) m.props.emplace_back("_flux", interesting_number(r));
            add.push_back({"MATL", write_matl(m), {}});
            break;
        }
        case 3: {
            std::string rgba;
            for (int i = 0; i < 256; ++i) put_i32(rgba, std::int32_t(r()));
            add.push_back({"RGBA", rgba, {}});
            break;
        }
        default: {
            static const std::vector<std::string> skipped = {"LAYR", "rOBJ", "rCAM", "NOTE", "IMAP", "MATT", "PACK"};
            std::string content;
            put_i32(content, uniform(r, 0, 3));
            Dict d{{"_type", "_bg"}, {"_name", interesting_number(r)}};
            put_dict(content, d);
            add.push_back({pick(r, skipped), content, {}});
            break;
        }
    }
    f.chunks.insert(f.chunks.begin() + long(at), add.begin(), add.end());
}

// One structural edit of `f`.
// A fresh scene-graph node id for `c` (a copy of a graph chunk: the loader refuses a duplicate id).
inline void renumber(Chunk& c, const File& f) {
    if ((c.id != "nTRN" && c.id != "nGRP" && c.id != "nSHP") || c.content.size() < 4) return;
    std::int32_t next = 0;
    for (std::int32_t i : node_ids(f)) next = std::max(next, i < INT32_MAX - 2 ? i + 1 : 0);
    std::string id;
    put_i32(id, next);
    c.content.replace(0, 4, id);
}

// The chunks [first, first + count) that move together: a SIZE with the XYZI after it, an XYZI with its SIZE.
inline std::pair<std::size_t, std::size_t> unit_at(const File& f, std::size_t i) {
    if (f.chunks[i].id == "SIZE" && i + 1 < f.chunks.size() && f.chunks[i + 1].id == "XYZI") return {i, 2};
    if (f.chunks[i].id == "XYZI" && i > 0 && f.chunks[i - 1].id == "SIZE") return {i - 1, 2};
    return {i, 1};
}

inline void mutate_file(File& f, Rng& r) {
    if (f.chunks.empty()) { add_chunk(f, r); return; }
    const std::size_t i = std::size_t(uniform(r, 0, int(f.chunks.size()) - 1));
    // Chunk-list edits keep a model's SIZE and XYZI together, except now and then (the loader's pairing checks).
    const auto [first, count] = uniform(r, 0, 7) ? unit_at(f, i) : std::pair<std::size_t, std::size_t>{i, 1};
    const int op = uniform(r, 0, 15);
    if (op == 0) {  // duplicate
        std::vector<Chunk> copy(f.chunks.begin() + long(first), f.chunks.begin() + long(first + count));
        if (uniform(r, 0, 7)) renumber(copy[0], f);
        f.chunks.insert(f.chunks.begin() + uniform(r, 0, int(f.chunks.size())), copy.begin(), copy.end());
    } else if (op == 1) {  // delete
        f.chunks.erase(f.chunks.begin() + long(first), f.chunks.begin() + long(first + count));
    } else if (op == 2) {  // move
        std::vector<Chunk> moved(f.chunks.begin() + long(first), f.chunks.begin() + long(first + count));
        f.chunks.erase(f.chunks.begin() + long(first), f.chunks.begin() + long(first + count));
        f.chunks.insert(f.chunks.begin() + uniform(r, 0, int(f.chunks.size())), moved.begin(), moved.end());
    } else if (op == 3) {
        add_chunk(f, r);
    } else if (op == 4) {
        f.version = uniform(r, 0, 7) ? pick(r, std::vector<int>{150, 200}) : pick(r, std::vector<int>{149, 201, 0, -1});
    } else {
        // Edit a chunk's fields: the chunk picked is of a kind the loader reads when there is one.
        Chunk& c = f.chunks[i];
        if (c.id == "SIZE") {
            mutate_size(c, r);
            if (uniform(r, 0, 7)) clip_xyzi(f, i);
        }
        else if (c.id == "XYZI") mutate_xyzi(f, i, r);
        else if (c.id == "RGBA") mutate_rgba(c, r);
        else if (c.id == "MATL") mutate_matl(c, r);
        else if (c.id == "nTRN") mutate_trn(c, f, r);
        else if (c.id == "nGRP") mutate_grp(c, f, r);
        else if (c.id == "nSHP") mutate_shp(c, f, r);
        else if (!c.content.empty()) c.content[std::size_t(uniform(r, 0, int(c.content.size()) - 1))] = char(r());
        else add_chunk(f, r);
    }
}

// The custom mutator: 1..3 structural edits of the (repaired) chunk list, or (1 in 5, or when the input is not a
// .vox file at all) byte mutation.
inline std::size_t mutate(std::uint8_t* data, std::size_t size, std::size_t max_size, unsigned seed) {
    Rng r(seed ? seed : 1);
    if (uniform(r, 0, 4) == 0) return LLVMFuzzerMutate(data, size, max_size);
    std::optional<File> f = parse(data, size, /*repair=*/true);
    if (!f) return LLVMFuzzerMutate(data, size, max_size);
    const int edits = uniform(r, 0, 2) == 0 ? uniform(r, 2, 3) : 1;
    for (int k = 0; k < edits; ++k) mutate_file(*f, r);
    const std::string out = serialize(*f);
    if (out.size() > max_size) return LLVMFuzzerMutate(data, size, max_size);
    std::memcpy(data, out.data(), out.size());
    return out.size();
}

// Cross-over: the chunks of one input with a run of the other's spliced in (models, materials or graph nodes from
// another file).
inline std::size_t cross_over(const std::uint8_t* d1, std::size_t s1, const std::uint8_t* d2, std::size_t s2,
                              std::uint8_t* out, std::size_t max_out, unsigned seed) {
    Rng r(seed ? seed : 1);
    std::optional<File> a = parse(d1, s1, true), b = parse(d2, s2, true);
    if (!a || !b || b->chunks.empty()) {
        const std::size_t n = std::min(s1, max_out);
        std::memcpy(out, d1, n);
        return LLVMFuzzerMutate(out, n, max_out);
    }
    // A model (SIZE + XYZI), a material, a palette or a skipped chunk of b; a scene-graph chunk of b gets a fresh
    // id (its references then point into a's graph: retargeted, not refused as a duplicate).
    const auto [from, len] = unit_at(*b, std::size_t(uniform(r, 0, int(b->chunks.size()) - 1)));
    std::vector<Chunk> add(b->chunks.begin() + long(from), b->chunks.begin() + long(from + len));
    renumber(add[0], *a);
    // A model goes after a's last model (its index is then a's model count: a new nSHP may refer to it).
    std::size_t at = std::size_t(uniform(r, 0, int(a->chunks.size())));
    if (add[0].id == "SIZE") {
        at = 0;
        for (std::size_t k = 0; k < a->chunks.size(); ++k)
            if (a->chunks[k].id == "SIZE" || a->chunks[k].id == "XYZI") at = k + 1;
    }
    a->chunks.insert(a->chunks.begin() + long(at), add.begin(), add.end());
    const std::string s = serialize(*a);
    if (s.size() > max_out) {
        const std::size_t n = std::min(s1, max_out);
        std::memcpy(out, d1, n);
        return n;
    }
    std::memcpy(out, s.data(), s.size());
    return s.size();
}

}  // namespace ngi::fuzz::vox
