#pragma once
/** \file BlobCodec.h
 * Packing of the store's BLOB columns (internal to keygrid_store): fixed-size little-endian
 * fields, no padding; the layouts are listed in doc/session-store.md.
 */
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace keygrid::store::detail
{
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the session store writes little-endian BLOBs by memcpy");

class BlobWriter
{
   public:
	explicit BlobWriter(std::size_t reserveBytes = 0) { m_bytes.reserve(reserveBytes); }
	template <class T>
	void put(const T& v)
	{
		static_assert(std::is_trivially_copyable_v<T>);
		const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
		m_bytes.insert(m_bytes.end(), p, p + sizeof(T));
	}
	void putBytes(const void* data, std::size_t n)
	{
		const auto* p = static_cast<const std::uint8_t*>(data);
		m_bytes.insert(m_bytes.end(), p, p + n);
	}
	template <class T>
	void putArray(const std::vector<T>& v)
	{
		static_assert(std::is_trivially_copyable_v<T>);
		putBytes(v.data(), v.size() * sizeof(T));
	}
	const std::vector<std::uint8_t>& bytes() const { return m_bytes; }
	std::vector<std::uint8_t>& bytes() { return m_bytes; }

   private:
	std::vector<std::uint8_t> m_bytes;
};

/** Reads back what BlobWriter wrote; throws std::runtime_error naming `what` when the BLOB is
 * shorter than its layout says (a damaged row). */
class BlobReader
{
   public:
	BlobReader(const std::uint8_t* data, std::size_t bytes, std::string what)
		: m_p(data), m_end(data + bytes), m_what(std::move(what))
	{
	}
	template <class T>
	T get()
	{
		static_assert(std::is_trivially_copyable_v<T>);
		T v;
		need(sizeof(T));
		std::memcpy(&v, m_p, sizeof(T));
		m_p += sizeof(T);
		return v;
	}
	void getBytes(void* out, std::size_t n)
	{
		need(n);
		if (n) std::memcpy(out, m_p, n);
		m_p += n;
	}
	template <class T>
	std::vector<T> getArray(std::size_t count)
	{
		std::vector<T> v(count);
		getBytes(v.data(), count * sizeof(T));
		return v;
	}
	/** Elements of size `elem` left (throws when the rest is not a whole number of them). */
	std::size_t remainingCount(std::size_t elem) const
	{
		const auto n = static_cast<std::size_t>(m_end - m_p);
		if (n % elem != 0)
			throw std::runtime_error(m_what + ": " + std::to_string(n) + " bytes, not a multiple of " + std::to_string(elem));
		return n / elem;
	}
	bool atEnd() const { return m_p == m_end; }

   private:
	void need(std::size_t n) const
	{
		if (static_cast<std::size_t>(m_end - m_p) < n)
			throw std::runtime_error(m_what + ": truncated (" + std::to_string(m_end - m_p) + " bytes left, " +
									 std::to_string(n) + " needed)");
	}
	const std::uint8_t* m_p;
	const std::uint8_t* m_end;
	std::string m_what;
};

}  // namespace keygrid::store::detail
