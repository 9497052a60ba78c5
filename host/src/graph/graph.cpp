#include "graph/graph.hpp"

#include <algorithm>
#include <limits>

namespace ngi::detail {

TensorId Graph::input(const Shape& shape, const std::string& name) {
    if (input_ != -1) throw Error("graph: only one input is supported");
    if (shape.size() == 0) throw InputError("graph input " + name + ": empty shape " + to_string(shape));
    tensors_.emplace_back(shape, name);
    input_ = TensorId(tensors_.size() - 1);
    return input_;
}

TensorId Graph::add(std::shared_ptr<Op> op, const std::vector<TensorId>& inputs, const std::string& name) {
    std::vector<Shape> shapes;
    for (TensorId t : inputs) shapes.push_back(tensors_.at(t).shape);
    Shape out;
    try {
        out = op->infer(shapes);
    } catch (const InputError& e) {
        throw InputError("graph node " + name + " (" + op->kind() + "): " + e.what());
    }
    const int node = int(nodes_.size());
    Tensor t{out, name, node};
    if (op->in_place()) {
        if (inputs.empty() || !(shapes[0] == out)) throw Error("graph node " + name + ": in-place op changes the shape");
        for (int c : tensors_[inputs[0]].consumers)
            if (c != node) throw Error("graph node " + name + ": in-place op on " + tensors_[inputs[0]].name +
                                       ", which another node already reads");
        t.parent = inputs[0];
    }
    for (TensorId in : inputs) tensors_[in].consumers.push_back(node);
    tensors_.push_back(t);
    nodes_.push_back({std::move(op), inputs, TensorId(tensors_.size() - 1), name});
    return nodes_.back().output;
}

TensorId Graph::concat(const std::vector<TensorId>& inputs, const std::string& name) {
    if (inputs.empty()) throw Error("graph concat " + name + ": no inputs");
    Shape s = tensors_.at(inputs[0]).shape;
    s.c = 0;
    for (TensorId t : inputs) {
        const Shape& x = tensors_.at(t).shape;
        if (x.h != s.h || x.w != s.w)
            throw InputError("graph concat " + name + ": " + tensors_[t].name + " is " + to_string(x) +
                             ", expected spatial size " + std::to_string(s.h) + "x" + std::to_string(s.w));
        s.c += x.c;
    }
    tensors_.emplace_back(s, name);
    const TensorId cat = TensorId(tensors_.size() - 1);
    tensors_[cat].is_concat = true;
    std::size_t offset = 0;
    for (TensorId t : inputs) {
        const TensorId r = root(t);
        if (r == input_ || r == cat)  // r == cat: t is twice in this concat (placing it again would loop)
            throw Error("graph concat " + name + ": " + tensors_[t].name +
                        " is already placed (the graph input, or twice in this concat; copy it first)");
        // t may itself be an in-place alias of r at offset 0; place the root.
        tensors_[r].parent = cat;
        tensors_[r].offset = offset;
        offset += tensors_[t].shape.size();
    }
    return cat;
}

bool Graph::placeable(TensorId t) const {
    if (t < 0 || t >= TensorId(tensors_.size())) throw Error("graph: tensor id out of range");
    const TensorId r = root(t);
    return r != input_ && !tensors_[r].is_concat;
}

TensorId Graph::root(TensorId t) const {
    while (tensors_[t].parent != -1) t = tensors_[t].parent;
    return t;
}

View Graph::view(TensorId t) const {
    return View{arena_.get(), root_offset_[t], tensors_[t].shape};
}

void Graph::compile(Context& ctx) {
    if (output_ < 0) throw Error("graph: no output set");
    const int n = int(nodes_.size());
    // Steps: 0 = input upload, node i = i + 1, n + 1 = output download.
    std::vector<int> alloc_of(tensors_.size(), -1);
    std::vector<Allocation> allocs;
    for (TensorId t = 0; t < TensorId(tensors_.size()); ++t) {
        const TensorId r = root(t);
        if (alloc_of[r] == -1) {
            alloc_of[r] = int(allocs.size());
            allocs.push_back({tensors_[r].shape.size(), std::numeric_limits<int>::max(), -1});
        }
        alloc_of[t] = alloc_of[r];
    }
    for (TensorId t = 0; t < TensorId(tensors_.size()); ++t) {
        Allocation& a = allocs[alloc_of[t]];
        const int def = t == input_ ? 0 : tensors_[t].producer >= 0 ? tensors_[t].producer + 1 : a.first;
        a.first = std::min(a.first, def);
        a.last = std::max(a.last, def);
        for (int c : tensors_[t].consumers) a.last = std::max(a.last, c + 1);
        if (t == output_) a.last = n + 1;
    }
    for (auto& a : allocs) {  // a concat whose members are produced later than itself is defined: members' defs
        if (a.first == std::numeric_limits<int>::max()) a.first = 0;
        a.last = std::max(a.last, a.first);
    }
    plan_ = plan_arena(allocs);
    if (plan_.arena_size > std::size_t(std::numeric_limits<int>::max()))
        throw Error("graph: arena of " + std::to_string(plan_.arena_size) + " floats exceeds the 2^31 index range");

    root_offset_.assign(tensors_.size(), 0);
    for (TensorId t = 0; t < TensorId(tensors_.size()); ++t) {
        std::size_t off = 0;
        TensorId u = t;
        while (tensors_[u].parent != -1) { off += tensors_[u].offset; u = tensors_[u].parent; }
        root_offset_[t] = plan_.offsets[alloc_of[u]] + off;
    }
    scratch_floats_ = 1;
    for (const Node& node : nodes_) {
        std::vector<Shape> shapes;
        for (TensorId t : node.inputs) shapes.push_back(tensors_[t].shape);
        scratch_floats_ = std::max(scratch_floats_, node.op->scratch_floats(shapes));
    }
    arena_ = ctx.alloc(plan_.arena_size * sizeof(float), "graph tensor arena");
    scratch_ = ctx.alloc(scratch_floats_ * sizeof(float), "graph scratch");
    elementwise_ = std::make_unique<Elementwise>(ctx);
    compiled_ = true;
}

void Graph::enqueue_nodes(Context& ctx, std::vector<std::vector<cl_event>>* events) {
    elementwise_->sanitize(ctx, view(input_), input_lo_, input_hi_);  // counted later: no stall here
    if (events) events->assign(nodes_.size(), {});
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
        const Node& node = nodes_[i];
        std::vector<View> ins;
        for (TensorId t : node.inputs) ins.push_back(view(t));
        node.op->enqueue(ctx, ins, view(node.output), scratch_.get(), events ? &(*events)[i] : nullptr);
    }
}

void Graph::enqueue(Context& ctx, cl_mem in, std::size_t in_offset, cl_mem out, std::size_t out_offset) {
    if (!compiled_) throw Error("graph: enqueue() before compile()");
    ctx.copy(in, in_offset, arena_.get(), view(input_).offset * sizeof(float), input_bytes(),
             ("graph input " + tensors_[input_].name).c_str());
    enqueue_nodes(ctx, nullptr);
    ctx.copy(arena_.get(), view(output_).offset * sizeof(float), out, out_offset, output_bytes(),
             ("graph output " + tensors_[output_].name).c_str());
}

int Graph::sanitized_count(Context& ctx) { return elementwise_->sanitized_count(ctx); }

RunStats Graph::run(Context& ctx, const float* input, float* output) {
    if (!compiled_) throw Error("graph: run() before compile()");
    RunStats stats;
    const View in = view(input_), out = view(output_);
    ctx.write(arena_, in.offset * sizeof(float), in.shape.size() * sizeof(float), input,
              ("graph input " + tensors_[input_].name).c_str());
    const bool profile = ctx.options().profiling;
    std::vector<std::vector<cl_event>> events;
    enqueue_nodes(ctx, profile ? &events : nullptr);
    ctx.read(arena_, out.offset * sizeof(float), out.shape.size() * sizeof(float), output,
             ("graph output " + tensors_[output_].name).c_str());
    stats.sanitized_inputs = elementwise_->sanitized_count(ctx);
    if (profile) {
        for (std::size_t i = 0; i < nodes_.size(); ++i) {
            NodeProfile p{nodes_[i].name, nodes_[i].op->kind()};
            std::vector<Shape> shapes;
            for (TensorId t : nodes_[i].inputs) shapes.push_back(tensors_[t].shape);
            p.gflop = nodes_[i].op->flops(shapes) * 1e-9;
            for (cl_event e : events[i]) {
                cl_ulong t0 = 0, t1 = 0;
                check(clGetEventProfilingInfo(e, CL_PROFILING_COMMAND_START, sizeof t0, &t0, nullptr),
                      "profile graph node", "clGetEventProfilingInfo");
                check(clGetEventProfilingInfo(e, CL_PROFILING_COMMAND_END, sizeof t1, &t1, nullptr),
                      "profile graph node", "clGetEventProfilingInfo");
                p.ms += double(t1 - t0) * 1e-6;
                ++p.launches;
                clReleaseEvent(e);
            }
            stats.nodes.push_back(p);
        }
    }
    return stats;
}

}  // namespace ngi::detail
