// The config fields the network families that began as the generator's config share (docs/MODEL_FORMAT.md "Config"):
// pix2pix_unet, deepillumination, mlp and neural_gi. Each family's parser calls these around its own fields, in this
// order: network_config_start, its shape fields, network_config_fields, its own section, network_config_end.
// Library-internal.
#pragma once
#include "models/config_fields.hpp"
#include "ngi/model.hpp"

namespace ngi::detail {

// "format_version", then "input_nc" (required, 1..kMaxChannels).
void network_config_start(const ConfigFields& f, ModelConfig& c);
// norm, bn_mode, bn_eps, dropout, dropout_p, dropout_seed, leaky_slope (into `unet`: c.unet for the U-Net
// families; mlp, which has no U-Net, checks them into a section it drops), input_layout, input_range, output_range,
// source, output_mode and ssgi. other_output_modes: whether the family has output modes other than "lightmap"
// ("indirect", "ssgi_residual" with its "ssgi" object); a family without them refuses any other value.
void network_config_fields(const ConfigFields& f, ModelConfig& c, ModelConfig::UNet& unet, bool other_output_modes);
// "training" (an object) and "required" against the fields these families know.
void network_config_end(const ConfigFields& f);

}  // namespace ngi::detail
