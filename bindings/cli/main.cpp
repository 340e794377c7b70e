// The brdfz command. Library errors arrive as exceptions; they are printed here as one line
// ("brdfz: FILE: reason") with a non-zero exit status: 1 for any bad input or failure, 2 only when
// compress --auto finds no candidate within the budget (compress.cpp throws CLI::RuntimeError(2)).
#include <exception>
#include <iostream>

#include "brdfz/errors.h"
#include "commands.h"

int main(int argc, char** argv) {
    CLI::App app{"brdfz: measured BRDFs, compactly stored"};
    app.require_subcommand(1);
    // Usage errors are one line too.
    app.failure_message([](const CLI::App*, const CLI::Error& e) {
        return "brdfz: " + brdfz::printable(e.what()) + " (brdfz --help)\n";
    });
    brdfz::cli::add_info(app);
    brdfz::cli::add_convert(app);
    brdfz::cli::add_eval(app);
    brdfz::cli::add_diff(app);
    brdfz::cli::add_demo(app);
    brdfz::cli::add_validate(app);
    brdfz::cli::add_sample(app);
    brdfz::cli::add_fit(app);
    brdfz::cli::add_compress(app);
    brdfz::cli::add_pca_train(app);
    brdfz::cli::add_formats(app);
    brdfz::cli::add_representations(app);
    brdfz::cli::add_export(app);
    brdfz::cli::add_view(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // CLI11 numbers its usage errors from 100 up; every one of them is bad input.
        const int code = app.exit(e);
        return code == 0 || code == 2 ? code : 1;
    } catch (const std::exception& e) {
        std::cout.flush();
        std::cerr << "brdfz: " << brdfz::printable(e.what()) << "\n";
        return 1;
    }
    return 0;
}
