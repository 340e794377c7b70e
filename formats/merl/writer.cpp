#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "brdfz/formats/merl.h"
#include "detail/atomic_file.h"
#include "detail/bytes.h"

namespace brdfz::merl {

void write(const std::string& path, const Table& table) {
    const GridSpec& g = table.grid();
    detail::AtomicFile file(path);
    const std::int32_t dims[3] = {detail::to_little_endian<std::int32_t>(g.n_theta_h),
                                  detail::to_little_endian<std::int32_t>(g.n_theta_d),
                                  detail::to_little_endian<std::int32_t>(g.n_phi_d)};
    file.write(dims, sizeof dims);

    const std::size_t n = table.bins();
    std::vector<double> chunk(std::min<std::size_t>(n, 1 << 16));
    for (int c = 0; c < 3; ++c) {
        for (std::size_t start = 0; start < n; start += chunk.size()) {
            const std::size_t count = std::min(chunk.size(), n - start);
            for (std::size_t k = 0; k < count; ++k) {
                const float v = table.at(start + k, c);
                chunk[k] = detail::to_little_endian(std::isnan(v) ? kUnmeasured : v / kScale[c]);
            }
            file.write(chunk.data(), count * sizeof(double));
        }
    }
    file.commit();
}

}  // namespace brdfz::merl
