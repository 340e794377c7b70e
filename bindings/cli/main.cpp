// The brdfz command. Library errors arrive as exceptions; they are printed here as one line
// ("brdfz: FILE: reason") with a non-zero exit status.
#include <exception>
#include <iostream>

#include "commands.h"

int main(int argc, char** argv) {
    CLI::App app{"brdfz: measured BRDFs, compactly stored"};
    app.require_subcommand(1);
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
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const std::exception& e) {
        std::cout.flush();
        std::cerr << "brdfz: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
