#pragma once
// A small argument parser: positionals, and "--name value" or "--flag" options
// declared up front, so that a mistyped option is an error, not ignored.

#include "facetrack/error.hpp"

#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace facetrack::tools {

class Args {
public:
    /// valued: options that take a value; flags: options that do not.
    Args(const std::vector<std::string>& argv, const std::set<std::string>& valued, const std::set<std::string>& flags = {}) {
        for (std::size_t i = 0; i < argv.size(); ++i) {
            const std::string& a = argv[i];
            if (a.rfind("--", 0) != 0 || a == "--") {
                positional_.push_back(a);
            } else if (flags.count(a)) {
                options_[a] = "";
            } else if (valued.count(a)) {
                if (i + 1 >= argv.size()) throw Error("option " + a + " needs a value");
                options_[a] = argv[++i];
            } else {
                throw Error("unknown option '" + a + "'; " + known(valued, flags));
            }
        }
    }
    const std::vector<std::string>& positional() const { return positional_; }
    bool has(const std::string& name) const { return options_.count(name) != 0; }
    std::string get(const std::string& name, const std::string& fallback = "") const {
        const auto it = options_.find(name);
        return it == options_.end() ? fallback : it->second;
    }
    double number(const std::string& name, double fallback) const {
        if (!has(name)) return fallback;
        try {
            std::size_t used = 0;
            const double v = std::stod(get(name), &used);
            if (used == get(name).size()) return v;
        } catch (const std::exception&) {}
        throw Error("option " + name + " expects a number, got '" + get(name) + "'");
    }

    /// A whole number within int's range: "1e12", "2.5" or "nan" is an error
    /// (a cast from such a double to int is undefined behaviour).
    int integer(const std::string& name, int fallback) const {
        if (!has(name)) return fallback;
        const std::string& text = options_.at(name);
        try {
            std::size_t used = 0;
            const long long v = std::stoll(text, &used);
            if (used == text.size() && v >= std::numeric_limits<int>::min() && v <= std::numeric_limits<int>::max())
                return static_cast<int>(v);
        } catch (const std::exception&) {}
        throw Error("option " + name + " expects a whole number, got '" + text + "'");
    }

private:
    /// What a mistyped option's error lists: "options with a value: --a, --b; flags: --help".
    static std::string known(const std::set<std::string>& valued, const std::set<std::string>& flags) {
        const auto list = [](const std::set<std::string>& names) {
            std::string out;
            for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
            return out.empty() ? std::string("none") : out;
        };
        return "options with a value: " + list(valued) + "; flags: " + list(flags);
    }

    std::vector<std::string> positional_;
    std::map<std::string, std::string> options_;
};

/// "a,b,,c" -> {"a", "b", "c"}: an option's comma-separated list, empty items dropped.
inline std::vector<std::string> splitList(const std::string& text) {
    std::vector<std::string> out;
    std::string item;
    for (const char c : text + ",") {
        if (c != ',') {
            item += c;
        } else if (!item.empty()) {
            out.push_back(item);
            item.clear();
        }
    }
    return out;
}

}  // namespace facetrack::tools
