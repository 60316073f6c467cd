#include <keygrid/slam/KeyFrameImageCache.h>

#include <stdexcept>

namespace keygrid::slam
{
namespace
{
std::size_t bytesOf(const cv::Mat& m) { return m.empty() ? 0 : m.total() * m.elemSize(); }
}  // namespace

KeyFrameImageCache::KeyFrameImageCache(std::size_t capacityBytes, const std::string& spillDir) : m_capacity(capacityBytes), m_file(spillDir) {}

void KeyFrameImageCache::put(sfm::KeyFrameId id, const KeyFrameImageData& images)
{
	std::lock_guard<std::mutex> lk(m_mutex);
	forget(id);
	Stored s;
	s.hasDepth = !images.depth.empty();
	s.hasColour = !images.colour.empty();
	m_stored[id] = s;
	remember(id, images);
}

bool KeyFrameImageCache::contains(sfm::KeyFrameId id) const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	return m_stored.count(id) != 0;
}

KeyFrameImageData KeyFrameImageCache::get(sfm::KeyFrameId id) const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	const auto it = m_stored.find(id);
	if (it == m_stored.end()) throw std::out_of_range("no images of keyframe " + std::to_string(id) + " in the image cache");
	const auto c = m_cached.find(id);
	if (c != m_cached.end())
	{
		m_stats.hits++;
		m_lru.splice(m_lru.begin(), m_lru, c->second.lru);
		return c->second.images;
	}
	m_stats.misses++;
	KeyFrameImageData out{m_file.read(it->second.depth), m_file.read(it->second.colour)};
	remember(id, out);
	return out;
}

bool KeyFrameImageCache::hasImages(const sfm::KeyFrame& kf) const
{
	if (!kf.depth.empty() || !kf.colour.empty()) return !kf.depth.empty() && !kf.colour.empty();
	std::lock_guard<std::mutex> lk(m_mutex);
	const auto it = m_stored.find(kf.id);
	return it != m_stored.end() && it->second.hasDepth && it->second.hasColour;
}

KeyFrameImageData KeyFrameImageCache::load(const sfm::KeyFrame& kf) const
{
	if (!kf.depth.empty() || !kf.colour.empty() || !contains(kf.id)) return {kf.depth, kf.colour};
	return get(kf.id);
}

void KeyFrameImageCache::remember(sfm::KeyFrameId id, const KeyFrameImageData& images) const
{
	const std::size_t bytes = bytesOf(images.depth) + bytesOf(images.colour);
	if (bytes > m_capacity)  // would not fit even alone
	{
		spill(id, images);
		return;
	}
	m_lru.push_front(id);
	m_cached[id] = Cached{images, bytes, m_lru.begin()};
	m_cachedBytes += bytes;
	while (m_cachedBytes > m_capacity)
	{
		const sfm::KeyFrameId oldest = m_lru.back();
		spill(oldest, m_cached.at(oldest).images);
		forget(oldest);
		m_stats.evictions++;
	}
}

void KeyFrameImageCache::spill(sfm::KeyFrameId id, const KeyFrameImageData& images) const
{
	Stored& s = m_stored.at(id);
	if (s.inFile) return;
	s.depth = m_file.append(images.depth);
	s.colour = m_file.append(images.colour);
	s.inFile = true;
}

void KeyFrameImageCache::forget(sfm::KeyFrameId id) const
{
	const auto c = m_cached.find(id);
	if (c == m_cached.end()) return;
	m_cachedBytes -= c->second.bytes;
	m_lru.erase(c->second.lru);
	m_cached.erase(c);
}

std::size_t KeyFrameImageCache::cachedBytes() const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	return m_cachedBytes;
}

std::size_t KeyFrameImageCache::cachedCount() const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	return m_cached.size();
}

KeyFrameImageCache::Stats KeyFrameImageCache::stats() const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	return m_stats;
}

}  // namespace keygrid::slam
