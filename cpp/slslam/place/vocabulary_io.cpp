// The vocabulary file: compact, little-endian, checksummed.
//
//   offset  size  field
//   0       8     magic "SLSVOCAB"
//   8       4     format version (uint32, kFormatVersion)
//   12      4     descriptor kind (uint32): 1 binary (uint8, Hamming), 2 float32 (L2)
//   16      4     descriptor cols (uint32): bytes (binary) or floats
//   20      4     branching k (uint32)
//   24      4     levels L (uint32)
//   28      4     node count (uint32), node 0 is the root
//   32      ...   per node: parent (int32, -1 for the root), word id (int32, -1 for inner nodes),
//                 IDF weight (float64), descriptor (cols bytes, or cols float32)
//   end-8   8     FNV-1a 64 of every byte before it
//
// Parents precede their children (parent < node index), which makes any accepted file a tree.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "slslam/core/byte_io.h"
#include "slslam/core/check.h"
#include "slslam/place/descriptor_space.h"
#include "slslam/place/vocabulary.h"

namespace slslam {

namespace {

constexpr char kMagic[8] = {'S', 'L', 'S', 'V', 'O', 'C', 'A', 'B'};
constexpr uint32_t kFormatVersion = 1;
constexpr uint32_t kKindBinary = 1;
constexpr uint32_t kKindFloat = 2;
constexpr size_t kHeaderBytes = 32;
constexpr size_t kChecksumBytes = 8;
constexpr uint32_t kMaxCols = 1 << 16;  // far beyond any descriptor; guards the size arithmetic

}  // namespace

// Largest IDF weight a word can have: log(N / n) with N images counted in 64 bits is below
// ln(2^64) = 44.4; a file holding more was not written by training [-].
constexpr double kMaxWordWeight = 64.0;

class VocabularyFile {
 public:
  static void Write(const Vocabulary& v, const std::string& path);
  static Vocabulary Read(const std::string& path);
  // The file's bytes without the checksum, and their checksum.
  static ByteWriter Serialize(const Vocabulary& v);

 private:
  static void CheckTree(const Vocabulary& v, const std::string& path);
};

ByteWriter VocabularyFile::Serialize(const Vocabulary& v) {
  const bool binary = v.descriptor_type_ == CV_8U;
  ByteWriter out;
  out.Bytes(kMagic, sizeof(kMagic));
  out.U32(kFormatVersion);
  out.U32(binary ? kKindBinary : kKindFloat);
  out.U32(static_cast<uint32_t>(v.cols_));
  out.U32(static_cast<uint32_t>(v.branching_));
  out.U32(static_cast<uint32_t>(v.levels_));
  out.U32(static_cast<uint32_t>(v.num_nodes()));
  std::vector<uint8_t> bytes(v.cols_);
  for (int n = 0; n < v.num_nodes(); ++n) {
    out.I32(v.parent_[n]);
    out.I32(v.word_of_node_[n]);
    out.F64(v.weight_[n]);
    if (binary) {
      const int words = v.words_per_descriptor_;
      place_detail::UnpackBinary(v.binary_.data() + static_cast<size_t>(n) * words, v.cols_,
                                 bytes.data());
      out.Bytes(bytes.data(), bytes.size());
    } else {
      for (int i = 0; i < v.cols_; ++i) out.F32(v.float_[static_cast<size_t>(n) * v.cols_ + i]);
    }
  }
  return out;
}

void VocabularyFile::Write(const Vocabulary& v, const std::string& path) {
  SLSLAM_CHECK(!v.empty(), path, ": cannot save an empty vocabulary");
  ByteWriter out = Serialize(v);
  out.U64(Fnv1a64(out.buffer().data(), out.buffer().size()));

  const std::string partial = path + ".partial";
  {
    std::ofstream file(partial, std::ios::binary | std::ios::trunc);
    SLSLAM_CHECK(file.is_open(), path, ": cannot open ", partial, " for writing");
    file.write(reinterpret_cast<const char*>(out.buffer().data()),
               static_cast<std::streamsize>(out.buffer().size()));
    file.close();
    if (!file) {
      std::remove(partial.c_str());
      throw std::invalid_argument(Message(path, ": writing ", partial, " failed (disk full?)"));
    }
  }
  if (std::rename(partial.c_str(), path.c_str()) != 0) {
    std::remove(partial.c_str());
    throw std::invalid_argument(Message(path, ": cannot rename ", partial, " to it"));
  }
}

Vocabulary VocabularyFile::Read(const std::string& path) {
  auto fail = [&path](const std::string& problem) {
    throw std::invalid_argument(Message(path, ": ", problem));
  };
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) fail("is a folder, not a vocabulary file");
  // A FIFO or a device would block or never end: only regular files are read.
  if (std::filesystem::exists(path, error) && !std::filesystem::is_regular_file(path, error)) {
    fail("is not a regular file (a FIFO, device or socket), not a vocabulary file");
  }
  std::ifstream file(path, std::ios::binary);
  if (!file.is_open()) fail("cannot open the vocabulary file (missing or unreadable)");
  const std::vector<uint8_t> data((std::istreambuf_iterator<char>(file)),
                                  std::istreambuf_iterator<char>());
  if (file.bad()) fail("read error");
  if (data.size() < sizeof(kMagic) || std::memcmp(data.data(), kMagic, sizeof(kMagic)) != 0) {
    fail("not an slslam vocabulary (the file does not start with \"SLSVOCAB\")");
  }
  if (data.size() < kHeaderBytes + kChecksumBytes) {
    fail(Message("truncated: ", data.size(), " bytes, shorter than the ",
                 kHeaderBytes + kChecksumBytes, "-byte header and checksum"));
  }
  ByteReader in(data.data() + sizeof(kMagic), kHeaderBytes - sizeof(kMagic), path);
  const uint32_t version = in.U32("format version");
  if (version > kFormatVersion) {
    fail(Message("format version ", version, " is newer than this slslam reads (", kFormatVersion,
                 "); upgrade slslam"));
  }
  if (version == 0) fail("format version 0 is not a valid version");
  const uint32_t kind = in.U32("header");
  const uint32_t cols = in.U32("header");
  const uint32_t branching = in.U32("header");
  const uint32_t levels = in.U32("header");
  const uint32_t nodes = in.U32("header");
  if (kind != kKindBinary && kind != kKindFloat) {
    fail(Message("unknown descriptor kind ", kind, " (1 binary, 2 float)"));
  }
  if (cols == 0 || cols > kMaxCols) fail(Message("descriptor width ", cols, " out of range"));
  if (branching < 2 || levels < 1 || levels > 64) {
    fail(Message("branching ", branching, " / levels ", levels, " out of range"));
  }
  if (nodes == 0) fail("no nodes");
  const uint64_t descriptor_bytes = kind == kKindBinary ? cols : 4ull * cols;
  const uint64_t expected =
      kHeaderBytes + uint64_t{nodes} * (16 + descriptor_bytes) + kChecksumBytes;
  if (data.size() != expected) {
    fail(Message("file is ", data.size(), " bytes but its header (", nodes, " nodes of ",
                 16 + descriptor_bytes, " bytes) needs ", expected,
                 data.size() < expected ? " (truncated)" : " (trailing data)"));
  }
  const size_t payload = data.size() - kChecksumBytes;
  const uint64_t stored = ByteReader(data.data() + payload, kChecksumBytes, path).U64("checksum");
  const uint64_t computed = Fnv1a64(data.data(), payload);
  if (stored != computed) {
    fail(Message("checksum mismatch (stored ", std::hex, stored, ", computed ", computed,
                 "): the file is corrupt"));
  }

  Vocabulary v;
  v.descriptor_type_ = kind == kKindBinary ? CV_8U : CV_32F;
  v.cols_ = static_cast<int>(cols);
  v.branching_ = static_cast<int>(branching);
  v.levels_ = static_cast<int>(levels);
  v.parent_.resize(nodes);
  v.word_of_node_.resize(nodes);
  v.weight_.resize(nodes);
  if (kind == kKindBinary) {
    v.words_per_descriptor_ = place_detail::WordsForBytes(v.cols_);
    v.binary_.assign(static_cast<size_t>(nodes) * v.words_per_descriptor_, 0);
  } else {
    v.float_.resize(static_cast<size_t>(nodes) * cols);
  }
  ByteReader body(data.data() + kHeaderBytes, payload - kHeaderBytes, path);
  for (uint32_t n = 0; n < nodes; ++n) {
    v.parent_[n] = body.I32("node");
    v.word_of_node_[n] = body.I32("node");
    v.weight_[n] = body.F64("node");
    if (kind == kKindBinary) {
      const cv::Mat row(1, v.cols_, CV_8U,
                        const_cast<uint8_t*>(body.Take(cols, "node descriptor")));
      place_detail::PackBinaryRow(
          row, 0, v.words_per_descriptor_,
          v.binary_.data() + static_cast<size_t>(n) * v.words_per_descriptor_);
    } else {
      for (uint32_t i = 0; i < cols; ++i)
        v.float_[static_cast<size_t>(n) * cols + i] = body.F32("node descriptor");
    }
  }
  CheckTree(v, path);
  v.BuildIndex();
  return v;
}

// The structure a checksum cannot vouch for (a file written by other code): a rooted tree no
// deeper than L with at most k children per node, leaves and words in one-to-one correspondence.
void VocabularyFile::CheckTree(const Vocabulary& v, const std::string& path) {
  auto fail = [&path](const std::string& problem) {
    throw std::invalid_argument(Message(path, ": ", problem));
  };
  const size_t n = v.parent_.size();
  if (v.parent_[0] != -1) fail("node 0 (the root) must have parent -1");
  std::vector<int> depth(n, 0), children(n, 0);
  for (size_t i = 1; i < n; ++i) {
    const int32_t p = v.parent_[i];
    if (p < 0 || static_cast<size_t>(p) >= i) {
      fail(Message("node ", i, " has parent ", p, ", not in [0, ", i, ")"));
    }
    depth[i] = depth[p] + 1;
    if (depth[i] > v.levels_) fail(Message("node ", i, " is deeper than ", v.levels_, " levels"));
    if (++children[p] > v.branching_) {
      fail(Message("node ", p, " has more than ", v.branching_, " children"));
    }
  }
  size_t leaves = 0;
  for (size_t i = 0; i < n; ++i) leaves += children[i] == 0 ? 1 : 0;
  std::vector<bool> seen(leaves, false);
  for (size_t i = 0; i < n; ++i) {
    const int32_t w = v.word_of_node_[i];
    const bool leaf = children[i] == 0;
    if (!leaf && w != -1) fail(Message("inner node ", i, " has word id ", w, " (must be -1)"));
    if (!leaf) continue;
    if (w < 0 || static_cast<size_t>(w) >= leaves || seen[w]) {
      fail(Message("leaf ", i, " has word id ", w, ": not unique in [0, ", leaves, ")"));
    }
    seen[w] = true;
    if (!(v.weight_[i] >= 0.0 && v.weight_[i] <= kMaxWordWeight)) {
      fail(Message("word ", w, " has weight ", v.weight_[i], " (an IDF weight is in [0, ",
                   kMaxWordWeight, "])"));
    }
  }
  for (const float value : v.float_) {
    if (!std::isfinite(value)) fail("a float descriptor holds a non-finite value");
  }
}

Vocabulary Vocabulary::Load(const std::string& path) { return VocabularyFile::Read(path); }

void Vocabulary::Save(const std::string& path) const { VocabularyFile::Write(*this, path); }

uint64_t Vocabulary::Checksum() const {
  if (empty()) return 0;
  ByteWriter out = VocabularyFile::Serialize(*this);
  return Fnv1a64(out.buffer().data(), out.buffer().size());
}

}  // namespace slslam
