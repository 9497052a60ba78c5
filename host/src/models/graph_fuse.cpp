// fuse_graph (graph_fuse.hpp): the loader's folds of a family "graph" node list, each one walk over the list with the
// maps of producers and readers kept up to date, linear in the node count. One walk reaches what repeating until
// nothing changes would: a fold only ever makes the node that reads its output foldable, and that node comes later.
// The conditions are those of the converter's fusion that this replaces (bindings/python/ngi/onnx_import.py before
// issue 49), several of them fuzz findings, plus the slope rules a hand-written or older file needs (the converter's
// own output met them by construction).
#include "models/graph_fuse.hpp"

#include <algorithm>
#include <cmath>

namespace ngi::detail {

namespace {

bool fuse_is_layer(NodeKind k) {
    return k == NodeKind::conv2d || k == NodeKind::conv_transpose2d || k == NodeKind::dense;
}
// The layers whose loader entry takes an input_activation (not dense: the converter once wrote one there, found by
// the fuzz target's load check, and the loader refused the file).
bool fuse_gathers(NodeKind k) { return k == NodeKind::conv2d || k == NodeKind::conv_transpose2d; }

bool fuse_is(const nlohmann::json& f, const char* key, const char* activation) {
    return f.contains(key) && f[key] == activation;
}
// The slope a leaky ReLU of node fields f uses (graph_model.cpp's node_activation: default 0.01).
float fuse_slope(const nlohmann::json& f) { return f.contains("slope") ? f["slope"].get<float>() : 0.01f; }

struct FuseWork {
    GraphNodeDesc node;
    GraphNodeWeights w;
    int out = 0;  // the tensor it makes now (original numbering: 0 = graph input, k + 1 = node k's output)
    bool removed = false;
};

// Scales layer `src`'s weights per output channel and gives it the bias bias * scale + shift, in double, rounded to
// float32 once; false (nothing changed) when a result is not a finite float32 (1e5 x 1e34: the network as written
// computes in float32 without that product, so the affine stays a node).
bool fuse_affine_into(FuseWork& src, const FuseWork& a, FusedGraph& out) {
    const int cout = src.node.out_channels;
    const StoredTensor& w = *src.w.w;
    const std::size_t count = w.data.size();
    const bool transposed = src.node.kind == NodeKind::conv_transpose2d;  // [in, out, kh, kw]; else [out, ...]
    const std::size_t inner = transposed ? count / (std::size_t(w.shape[0]) * std::size_t(w.shape[1]))
                                         : count / std::size_t(cout);
    auto scale = [&](int c) { return a.w.scale ? double(a.w.scale->data[std::size_t(c)]) : 1.0; };
    auto shift = [&](int c) { return a.w.shift ? double(a.w.shift->data[std::size_t(c)]) : 0.0; };
    auto nw = std::make_unique<StoredTensor>(StoredTensor{w.shape, "F32", std::vector<float>(count)});
    for (std::size_t i = 0; i < count; ++i) {
        const int c = int(transposed ? (i / inner) % std::size_t(cout) : i / inner);
        nw->data[i] = float(double(w.data[i]) * scale(c));
        if (!std::isfinite(nw->data[i])) return false;
    }
    auto nb = std::make_unique<StoredTensor>(StoredTensor{{cout}, "F32", std::vector<float>(std::size_t(cout))});
    for (int c = 0; c < cout; ++c) {
        const double b = src.w.b ? double(src.w.b->data[std::size_t(c)]) : 0.0;
        nb->data[std::size_t(c)] = float(b * scale(c) + shift(c));
        if (!std::isfinite(nb->data[std::size_t(c)])) return false;
    }
    src.w.w = nw.get();
    src.w.b = nb.get();
    out.made.push_back(std::move(nw));
    out.made.push_back(std::move(nb));
    return true;
}

// Activation node a into the epilogue of layer src, unless a leaky ReLU's slope would change: src's input_activation
// and activation share one `slope`.
bool fuse_activation_into(FuseWork& src, const FuseWork& a) {
    nlohmann::json& s = src.node.fields;
    const nlohmann::json& f = a.node.fields;
    const bool leaky = fuse_is(f, "activation", "leaky_relu");
    if (leaky && fuse_is(s, "input_activation", "leaky_relu") && fuse_slope(s) != fuse_slope(f)) return false;
    s["activation"] = f["activation"];
    if (leaky) s["slope"] = f.contains("slope") ? f["slope"] : nlohmann::json(0.01);
    return true;
}

// Pass 1: affines, then activations, into the layer that makes their input.
void fuse_into_producers(std::vector<FuseWork>& v, int graph_output, FusedGraph& out) {
    std::vector<int> readers(v.size() + 1, 0);  // per tensor; the graph output is read once more, at the end
    for (const FuseWork& n : v)
        for (int i : n.node.inputs) ++readers[std::size_t(i)];
    ++readers[std::size_t(graph_output)];
    std::vector<int> made_by(v.size() + 1, -1);  // tensor -> the node that makes it now
    for (std::size_t k = 0; k < v.size(); ++k) made_by[k + 1] = int(k);
    for (std::size_t k = 0; k < v.size(); ++k) {
        FuseWork& a = v[k];
        const bool affine = a.node.kind == NodeKind::affine;
        if (!affine && a.node.kind != NodeKind::activation) continue;
        const int s = made_by[std::size_t(a.node.inputs[0])];
        if (s < 0) continue;  // the graph input
        FuseWork& src = v[std::size_t(s)];
        // Its output read by this node alone, a layer, and no activation yet (an affine after one is no weight
        // scaling; a second activation would replace the first). A key present counts, as the converter judged.
        if (readers[std::size_t(src.out)] != 1 || !fuse_is_layer(src.node.kind) ||
            src.node.fields.contains("activation"))
            continue;
        if (affine ? !fuse_affine_into(src, a, out) : !fuse_activation_into(src, a)) continue;
        ++(affine ? out.affines : out.activations);
        src.node.folded.push_back(a.node.name);
        src.node.folded.insert(src.node.folded.end(), a.node.folded.begin(), a.node.folded.end());
        src.node.output = a.node.output;
        src.out = a.out;
        made_by[std::size_t(a.out)] = s;
        a.removed = true;
    }
}

// Pass 2: a ReLU / LeakyReLU read only by convolutions without an input activation becomes theirs. Folding one
// changes only its readers, which read nothing else (one input each), so no fold makes or unmakes another.
void fuse_into_readers(std::vector<FuseWork>& v, int graph_output, FusedGraph& out) {
    std::vector<std::vector<int>> users(v.size() + 1);  // tensor -> the remaining nodes that read it, in order
    for (std::size_t k = 0; k < v.size(); ++k)
        if (!v[k].removed)
            for (int i : v[k].node.inputs) users[std::size_t(i)].push_back(int(k));
    for (std::size_t k = 0; k < v.size(); ++k) {
        FuseWork& n = v[k];
        const nlohmann::json& f = n.node.fields;
        if (n.removed || n.node.kind != NodeKind::activation || n.out == graph_output ||
            !(fuse_is(f, "activation", "relu") || fuse_is(f, "activation", "leaky_relu")))
            continue;
        const bool leaky = fuse_is(f, "activation", "leaky_relu");
        const std::vector<int>& readers = users[std::size_t(n.out)];
        bool ok = !readers.empty();
        for (int r : readers) {
            const nlohmann::json& m = v[std::size_t(r)].node.fields;
            ok = ok && fuse_gathers(v[std::size_t(r)].node.kind) && !m.contains("input_activation") &&
                 // the converter's rules: one slope per node, never replaced
                 !(m.contains("slope") && f.contains("slope") && m["slope"] != f["slope"]) &&
                 !(m.contains("slope") && leaky) &&
                 // and a leaky output activation (default slope) keeps its slope
                 !(leaky && fuse_is(m, "activation", "leaky_relu") && fuse_slope(m) != fuse_slope(f));
        }
        if (!ok) continue;
        const int source = n.node.inputs[0];
        std::vector<int>& at_source = users[std::size_t(source)];
        at_source.erase(std::find(at_source.begin(), at_source.end(), int(k)));
        for (int r : readers) {
            FuseWork& m = v[std::size_t(r)];
            m.node.inputs = {source};
            at_source.push_back(r);
            m.node.fields["input_activation"] = f["activation"];
            if (leaky) m.node.fields["slope"] = f.contains("slope") ? f["slope"] : nlohmann::json(0.01);
            m.node.folded.push_back(n.node.name);
        }
        users[std::size_t(n.out)].clear();
        n.removed = true;
        ++out.input_activations;
    }
}

}  // namespace

FusedGraph fuse_graph(const GraphDesc& d, const std::vector<GraphNodeWeights>& weights) {
    FusedGraph out;
    std::vector<FuseWork> v(d.nodes.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = {d.nodes[k], weights.at(k), int(k) + 1, false};
    fuse_into_producers(v, d.output, out);
    fuse_into_readers(v, d.output, out);
    // The remaining nodes, their inputs renumbered (a folded node's output is now its producer's).
    out.desc.layout = d.layout;
    out.desc.input_name = d.input_name;
    out.desc.input_nc = d.input_nc;
    std::vector<int> index(v.size() + 1, -1);
    index[0] = 0;
    for (FuseWork& n : v) {
        if (n.removed) continue;
        for (int& i : n.node.inputs) {
            i = index[std::size_t(i)];
            if (i < 0) throw Error("graph fusion: node '" + n.node.name + "' reads a tensor no node makes");  // a bug
        }
        out.desc.nodes.push_back(std::move(n.node));
        out.weights.push_back(n.w);
        index[std::size_t(n.out)] = int(out.desc.nodes.size());
    }
    out.desc.output = index[std::size_t(d.output)];
    return out;
}

}  // namespace ngi::detail
