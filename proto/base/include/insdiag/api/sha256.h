// SHA-256 of bytes, for the digests the API and the knowledge base keep: a
// token's secret, a migration's text (the upload's sample digest is
// run_codec.h's SampleDigest).
#pragma once

#include <string>
#include <string_view>

namespace insdiag::api {

// SHA-256 of `bytes`: the 32 raw bytes of the digest.
std::string Sha256(std::string_view bytes);

}  // namespace insdiag::api
