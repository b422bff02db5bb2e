// `candela help` (as --help and the manual page list it) and `candela completion bash`: the
// shell completion script, written from the same CLI11 app as --help and the manual page, so a
// new flag is completed as soon as it is declared.
#include "commands.h"

#include "candela/util/error.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>
#include <sstream>

namespace candela::app {

namespace {

/// The names of an option as typed: "-s", "--spp".
std::vector<std::string> typed_names(const CLI::Option& o) {
    std::vector<std::string> names;
    for (const std::string& s : o.get_snames())
        names.push_back("-" + s);
    for (const std::string& l : o.get_lnames())
        names.push_back("--" + l);
    return names;
}

/// The commands `app` declares, in the order --help lists them.
std::vector<const CLI::App*> commands_of(const CLI::App& app) {
    return app.get_subcommands([](const CLI::App* s) { return !s->get_name().empty(); });
}

/// `words` joined by spaces.
std::string joined(const std::vector<std::string>& words) {
    std::string out;
    for (const std::string& w : words)
        out += (out.empty() ? "" : " ") + w;
    return out;
}

} // namespace

std::string bash_completion(const CLI::App& app) {
    std::vector<std::string> command_names;
    for (const CLI::App* sub : commands_of(app))
        command_names.push_back(sub->get_name());
    const std::string commands = joined(command_names);

    std::ostringstream flags, file_valued, other_valued;
    std::vector<std::string> top;
    for (const CLI::Option* o : app.get_options())
        for (const std::string& n : typed_names(*o))
            top.push_back(n);
    flags << "    top) echo '" << joined(top) << "' ;;\n";
    for (const CLI::App* sub : commands_of(app)) {
        std::vector<std::string> all, files, others;
        for (const CLI::Option* o : sub->get_options()) {
            if (o->get_positional()) continue;
            const std::vector<std::string> names = typed_names(*o);
            all.insert(all.end(), names.begin(), names.end());
            if (o->get_type_size() == 0) continue; // a flag: no value follows
            // A TEXT value is a path or a name: offer file names; a number gets no completion.
            std::vector<std::string>& valued = o->get_type_name() == "TEXT" ? files : others;
            for (const std::string& n : names)
                valued.push_back(sub->get_name() + ":" + n);
        }
        flags << "    " << sub->get_name() << ") echo '" << joined(all) << "' ;;\n";
        if (!files.empty()) file_valued << " " << joined(files);
        if (!others.empty()) other_valued << " " << joined(others);
    }

    std::ostringstream s;
    s << "# bash completion for candela: its commands and each command's flags.\n"
         "# Written by 'candela completion bash' from the option table of --help.\n"
         "# Install: share/bash-completion/completions/candela (cmake --install does), or\n"
         "#   source <(candela completion bash)\n"
         "\n"
         "_candela_flags() {\n"
         "    case \"$1\" in\n"
      << flags.str()
      << "    esac\n"
         "}\n"
         "\n"
         "_candela() {\n"
         "    local cur=\"${COMP_WORDS[COMP_CWORD]}\" prev=\"\" cmd=\"\" i\n"
         "    local commands='"
      << commands
      << "'\n"
         "    local file_valued=' "
      << file_valued.str()
      << " '\n"
         "    local other_valued=' "
      << other_valued.str()
      << " '\n"
         "    if [ \"$COMP_CWORD\" -gt 0 ]; then prev=\"${COMP_WORDS[COMP_CWORD - 1]}\"; fi\n"
         "    for ((i = 1; i < COMP_CWORD; i++)); do\n"
         "        case \" $commands \" in\n"
         "        *\" ${COMP_WORDS[i]} \"*) cmd=\"${COMP_WORDS[i]}\"; break ;;\n"
         "        esac\n"
         "    done\n"
         "    # 'candela SCENE.dae [flags]' and the CS184 order 'candela -t 1 SCENE.dae' render.\n"
         "    if [ -z \"$cmd\" ] && [ \"$COMP_CWORD\" -gt 1 ]; then cmd=render; fi\n"
         "    case \"$cmd\" in\n"
         "    help) COMPREPLY=($(compgen -W \"$commands --man\" -- \"$cur\")); return ;;\n"
         "    completion) COMPREPLY=($(compgen -W 'bash' -- \"$cur\")); return ;;\n"
         "    esac\n"
         "    case \"$other_valued\" in\n"
         "    *\" $cmd:$prev \"*) COMPREPLY=(); return ;;\n"
         "    esac\n"
         "    case \"$file_valued\" in\n"
         "    *\" $cmd:$prev \"*) COMPREPLY=($(compgen -f -- \"$cur\")); return ;;\n"
         "    esac\n"
         "    if [[ \"$cur\" == -* ]]; then\n"
         "        COMPREPLY=($(compgen -W \"$(_candela_flags \"${cmd:-top}\")\" -- \"$cur\"))\n"
         "    elif [ -z \"$cmd\" ]; then\n"
         "        COMPREPLY=($(compgen -W \"$commands\" -- \"$cur\") $(compgen -d -- \"$cur\")\n"
         "            $(compgen -f -X '!*.dae' -- \"$cur\"))\n"
         "    else\n"
         "        COMPREPLY=($(compgen -f -- \"$cur\"))\n"
         "    fi\n"
         "}\n"
         "complete -o filenames -F _candela candela\n";
    return s.str();
}

void add_help_command(CLI::App& app) {
    // main() answers `help` before CLI11 parses (it is `COMMAND --help`); the declaration is
    // what --help, the manual page and the completion list.
    CLI::App* cmd = app.add_subcommand(
        "help", "Show the commands, or a command's flags ('candela help render' is 'candela "
                "render --help')");
    cmd->add_option("command")->description("The command whose flags to show");
    cmd->add_flag("--man", "Print the manual page (roff) instead");
}

void add_completion_command(CLI::App& app, int* status) {
    auto shell = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand(
        "completion", "Print the shell completion script (bash): source <(candela completion "
                      "bash); cmake --install installs it");
    cmd->add_option("shell", *shell, "The shell: bash")->required();
    const CLI::App* top = &app;
    cmd->callback([shell, top, status] {
        if (*shell != "bash")
            throw Error(ErrorKind::Usage,
                        "completion: no completion for shell '" + *shell + "' (there is: bash)");
        std::fputs(bash_completion(*top).c_str(), stdout);
        *status = 0;
    });
}

} // namespace candela::app
