// The config fields the generator-descended network families share (models/network_config.hpp).
#include "models/network_config.hpp"

#include "models/float_field.hpp"
#include "models/ssgi_config.hpp"

namespace ngi::detail {

void network_config_start(const ConfigFields& f, ModelConfig& c) {
    f.format_version();
    c.input_nc = int(f.integer("input_nc", 1, kMaxChannels, 0, true));
}

void network_config_fields(const ConfigFields& f, ModelConfig& c, ModelConfig::UNet& u, bool other_output_modes) {
    f.string("norm", {"batch"}, "batch", false);
    u.bn_mode = f.string("bn_mode", {"running", "per_image"}, u.bn_mode, false);
    u.bn_eps = f.number("bn_eps", 0.0, 1.0, true, false, u.bn_eps);
    u.dropout = f.string("dropout", {"off", "seeded"}, u.dropout, false);
    u.dropout_p = f.number("dropout_p", 0.0, 1.0, false, true, u.dropout_p);  // 1 would divide by 1 - p = 0
    u.dropout_seed = std::uint32_t(f.integer("dropout_seed", 0, 0xffffffffll, u.dropout_seed, false));
    u.leaky_slope = f.number("leaky_slope", 0.0, 1.0, false, false, u.leaky_slope);
    if (f.has("input_layout") && !read_input_layout(f.at("input_layout"), c.input_nc, c.input_layout))
        throw f.fail("input_layout", input_layout_rule(c.input_nc));
    f.range("input_range", c.input_range);
    f.range("output_range", c.output_range);
    c.source = f.string("source", {}, c.source, false);
    c.output_mode = f.string("output_mode", {"lightmap", "indirect", "ssgi_residual"}, c.output_mode, false);
    // Only the pipeline's pix2pix generators compose their output with the frame's direct light (neural_gi
    // predicts indirect light by construction, through its own renderer; the others are not lightmap generators).
    if (c.output_mode != "lightmap" && !other_output_modes)
        throw InputError(f.what() + "field 'output_mode' is \"" + c.output_mode +
                         "\", which only family pix2pix_unet supports; this is family " + c.family +
                         " (use \"lightmap\" or leave the key out)");
    if (c.output_mode == "ssgi_residual") {
        // A network that corrects the SSGI rung (docs/CONVENTIONS.md section 8): the gather's settings travel with
        // it, its input is the front view plus the SSGI estimate, and its output is added to that estimate in the
        // encoded domain, so the two ranges must be one.
        if (!f.has("ssgi")) throw f.fail("ssgi", "an object of the gather's settings for output_mode ssgi_residual");
        c.ssgi = parse_ssgi_gather(f.at("ssgi"), f.what());
        if (c.input_nc != kSsgiResidualInputs)
            throw f.fail("input_nc", std::to_string(kSsgiResidualInputs) + " for output_mode ssgi_residual (the front "
                                     "view's 10 channels and the SSGI estimate's 3)");
        if (c.input_range[0] != c.output_range[0] || c.input_range[1] != c.output_range[1])
            throw InputError(f.what() + "output_mode ssgi_residual adds the network's output to its SSGI input "
                             "channels: input_range and output_range must be equal");
    } else if (f.has("ssgi")) {
        throw InputError(f.what() + "field 'ssgi' is only read with output_mode \"ssgi_residual\"; this model's is \"" +
                         c.output_mode + "\"");
    }
}

void network_config_end(const ConfigFields& f) {
    if (f.has("training") && !f.at("training").is_object()) throw f.fail("training", "an object");
    // The four families shared one parser until issue 49, so each still accepts the others' field names in "required".
    check_fields(f, {"format_version", "family", "input_nc", "output_nc", "ngf", "num_downs", "norm", "bn_mode",
                     "bn_eps", "dropout", "dropout_p", "dropout_seed", "leaky_slope", "input_layout", "input_range",
                     "output_range", "source", "training", "required", "layers", "encoding", "ao", "neural_gi",
                     "output_mode", "ssgi"});
}

}  // namespace ngi::detail
