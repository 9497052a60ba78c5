#include "frame_report.hpp"

#include <cstdio>
#include <filesystem>

#include "ngi/files.hpp"
#include "ngi/render.hpp"

namespace ngi_cli {

std::string sanitized_files_text(const ngi::FrameReadStats& stats) {
    std::string text;
    for (const ngi::SanitizedFile& s : stats.sanitized) {
        if (!text.empty()) text += "; ";
        text += s.file + ":";
        // Appended piece by piece: GCC 12's -Wrestrict misfires on `"literal" + std::string&&`.
        if (s.nan) text.append(" ").append(std::to_string(s.nan)).append(" NaN");
        if (s.inf) text.append(s.nan ? ", " : " ").append(std::to_string(s.inf)).append(" Inf");
    }
    return text;
}

void warn_frame_sanitized(const char* command, const std::string& frame_dir, const ngi::FrameReadStats& stats) {
    if (stats.total_sanitized() == 0) return;
    std::fprintf(stderr,
                 "ngi %s: warning: %s: %zu NaN/Inf values replaced on read (%s); scores against its reference are "
                 "not valid\n",
                 command, frame_dir.c_str(), stats.total_sanitized(), sanitized_files_text(stats).c_str());
}

void warn_noisy_direct_light(const char* command, const std::string& frame_dir) {
    const std::string path = (std::filesystem::path(frame_dir) / "render.json").string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return;
    int spp = 0;
    try {
        const nlohmann::json j = nlohmann::json::parse(ngi::read_input_file(path, "read", 1 << 20));
        const nlohmann::json& v = j.at("settings").at("feature_spp");
        if (!v.is_number_integer()) return;
        spp = v.get<int>();
    } catch (const std::exception&) {
        return;  // not ngi render's file, or not one it wrote: nothing is known of the noise
    }
    if (spp > 0 && spp < ngi::kEngineFeatureSpp / 4)
        std::fprintf(stderr,
                     "ngi %s: warning: %s: the direct light was rendered at %d spp (render.json): noisy, where an "
                     "engine's is converged (ngi render's default is %d spp); scores measure the noise too\n",
                     command, frame_dir.c_str(), spp, ngi::kEngineFeatureSpp);
}

namespace {

void null_scores(nlohmann::json& j, const std::string& note) {
    if (!j.is_object()) return;
    if (j.contains("mse") && j.contains("psnr") && j.contains("ssim")) {
        j = {{"mse", nullptr}, {"psnr", nullptr}, {"ssim", nullptr}, {"note", note}};
        return;
    }
    for (auto& [key, value] : j.items()) null_scores(value, note);
}

}  // namespace

void mark_scores(nlohmann::json& metrics, const ngi::FrameReadStats& stats) {
    if (metrics.is_null()) return;
    const bool valid = stats.total_sanitized() == 0;
    if (!valid) {
        null_scores(metrics, "not scored: the frame's files held " + std::to_string(stats.total_sanitized()) +
                                 " NaN/Inf values, replaced on read (" + sanitized_files_text(stats) +
                                 "); a score would compare the replacements");
        nlohmann::json files = nlohmann::json::array();
        for (const ngi::SanitizedFile& s : stats.sanitized)
            files.push_back({{"file", s.file}, {"nan", s.nan}, {"inf", s.inf}});
        metrics["frame_sanitized"] = files;
    }
    metrics["scores_valid"] = valid;
}

}  // namespace ngi_cli
