// Fixed-width little-endian encoding for slslam's binary files, whatever the host's byte order,
// and the FNV-1a 64 checksum they carry. The reader checks every read against the bytes left, so
// a count or length read from a damaged or hostile file can neither overrun the buffer nor make
// the caller allocate more than the file could hold.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "slslam/core/check.h"

namespace slslam {

// FNV-1a, 64 bits, over `size` bytes.
inline uint64_t Fnv1a64(const uint8_t* data, size_t size) {
  uint64_t hash = 0xcbf29ce484222325ull;  // FNV offset basis
  for (size_t i = 0; i < size; ++i) {
    hash ^= data[i];
    hash *= 0x100000001b3ull;  // FNV prime
  }
  return hash;
}

inline bool HostIsLittleEndian() {
  const uint16_t probe = 1;
  uint8_t first;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

// Appends values to a byte buffer.
class ByteWriter {
 public:
  void Bytes(const void* data, size_t size) {
    const auto* p = static_cast<const uint8_t*>(data);
    buffer_.insert(buffer_.end(), p, p + size);
  }
  void U8(uint8_t v) { buffer_.push_back(v); }
  void U32(uint32_t v) {
    for (int i = 0; i < 4; ++i) buffer_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  void U64(uint64_t v) {
    for (int i = 0; i < 8; ++i) buffer_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  void I32(int32_t v) { U32(static_cast<uint32_t>(v)); }
  void I64(int64_t v) { U64(static_cast<uint64_t>(v)); }
  void F32(float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    U32(bits);
  }
  void F64(double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, 8);
    U64(bits);
  }
  // A string as its byte count (uint32) and its bytes.
  void String(const std::string& s) {
    U32(static_cast<uint32_t>(s.size()));
    Bytes(s.data(), s.size());
  }
  // `count` elements of `element_bytes` each (1, 2, 4 or 8) in host order, written little-endian.
  void Elements(const void* data, size_t count, size_t element_bytes) {
    if (HostIsLittleEndian() || element_bytes == 1) {
      Bytes(data, count * element_bytes);
      return;
    }
    const auto* p = static_cast<const uint8_t*>(data);
    for (size_t e = 0; e < count; ++e, p += element_bytes) {
      for (size_t b = element_bytes; b-- > 0;) buffer_.push_back(p[b]);
    }
  }
  // Overwrites the 8 bytes at `offset` (written earlier) with v, little-endian: sizes and
  // checksums known only once what follows them is written.
  void PatchU64(size_t offset, uint64_t v) {
    for (int i = 0; i < 8; ++i) buffer_.at(offset + i) = static_cast<uint8_t>(v >> (8 * i));
  }
  std::vector<uint8_t>& buffer() { return buffer_; }
  size_t size() const { return buffer_.size(); }

 private:
  std::vector<uint8_t> buffer_;
};

// Reads values from [data, data + size). A read past the end throws std::invalid_argument
// "<source>: truncated ...", naming what was being read.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size, const std::string& source)
      : p_(data), end_(data + size), source_(&source) {}

  size_t remaining() const { return static_cast<size_t>(end_ - p_); }
  const std::string& source() const { return *source_; }

  // Throws std::invalid_argument "<source>: <problem>".
  [[noreturn]] void Fail(const std::string& problem) const {
    ThrowInvalidArgument(Message(*source_, ": ", problem));
  }

  // The next n bytes; `what` names them in the error.
  const uint8_t* Take(size_t n, const char* what) {
    if (n > remaining()) {
      ThrowInvalidArgument(
          Message(*source_, ": truncated: ", what, " needs ", n, " bytes, ", remaining(), " left"));
    }
    const uint8_t* at = p_;
    p_ += n;
    return at;
  }
  uint8_t U8(const char* what) { return *Take(1, what); }
  uint32_t U32(const char* what) {
    const uint8_t* p = Take(4, what);
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(p[i]) << (8 * i);
    return v;
  }
  uint64_t U64(const char* what) {
    const uint8_t* p = Take(8, what);
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(p[i]) << (8 * i);
    return v;
  }
  int32_t I32(const char* what) { return static_cast<int32_t>(U32(what)); }
  int64_t I64(const char* what) { return static_cast<int64_t>(U64(what)); }
  float F32(const char* what) {
    const uint32_t bits = U32(what);
    float v;
    std::memcpy(&v, &bits, 4);
    return v;
  }
  double F64(const char* what) {
    const uint64_t bits = U64(what);
    double v;
    std::memcpy(&v, &bits, 8);
    return v;
  }
  // A string written by ByteWriter::String, at most max_bytes long.
  std::string String(size_t max_bytes, const char* what) {
    const uint32_t n = U32(what);
    if (n > max_bytes) {
      ThrowInvalidArgument(Message(*source_, ": ", what, " is ", n, " bytes long, more than the ",
                                   max_bytes, " allowed"));
    }
    const uint8_t* p = Take(n, what);
    return std::string(reinterpret_cast<const char*>(p), n);
  }
  // A count (uint32) of elements taking at least min_bytes_each bytes each, checked against the
  // bytes left before anyone allocates for it.
  uint32_t Count(size_t min_bytes_each, const char* what) {
    const uint32_t n = U32(what);
    if (static_cast<uint64_t>(n) * min_bytes_each > remaining()) {
      ThrowInvalidArgument(Message(*source_, ": ", what, " is ", n, " but only ", remaining(),
                                   " bytes are left (", min_bytes_each, " at least per entry)"));
    }
    return n;
  }
  // `count` elements of `element_bytes` each, stored little-endian, into host order at `out`.
  void Elements(void* out, size_t count, size_t element_bytes, const char* what) {
    if (element_bytes > 0 && count > remaining() / element_bytes) {
      ThrowInvalidArgument(Message(*source_, ": truncated: ", what, " needs ", count, " x ",
                                   element_bytes, " bytes, ", remaining(), " left"));
    }
    const uint8_t* p = Take(count * element_bytes, what);
    if (HostIsLittleEndian() || element_bytes == 1) {
      if (count > 0) std::memcpy(out, p, count * element_bytes);
      return;
    }
    auto* q = static_cast<uint8_t*>(out);
    for (size_t e = 0; e < count; ++e, q += element_bytes, p += element_bytes) {
      for (size_t b = 0; b < element_bytes; ++b) q[b] = p[element_bytes - 1 - b];
    }
  }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
  const std::string* source_;
};

}  // namespace slslam
