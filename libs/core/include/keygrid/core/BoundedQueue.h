#pragma once
/** \file BoundedQueue.h
 * A typed, bounded, closable FIFO joining two threads (producer blocks when full, consumer
 * blocks when empty; close() wakes both and ends the stream).
 */
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>

namespace keygrid::core
{
template <typename T>
class BoundedQueue
{
   public:
	explicit BoundedQueue(std::size_t capacity) : m_capacity(capacity ? capacity : 1) {}

	/** Blocks while full. Returns false if the queue was closed. */
	bool push(T item)
	{
		std::unique_lock<std::mutex> lk(m_mutex);
		m_notFull.wait(lk, [&] { return m_closed || m_items.size() < m_capacity; });
		if (m_closed) return false;
		m_items.push_back(std::move(item));
		m_notEmpty.notify_one();
		return true;
	}

	/** Blocks while empty; nullopt once closed and drained. */
	std::optional<T> pop()
	{
		std::unique_lock<std::mutex> lk(m_mutex);
		m_notEmpty.wait(lk, [&] { return m_closed || !m_items.empty(); });
		if (m_items.empty()) return std::nullopt;
		T item = std::move(m_items.front());
		m_items.pop_front();
		m_notFull.notify_one();
		return item;
	}

	void close()
	{
		std::lock_guard<std::mutex> lk(m_mutex);
		m_closed = true;
		m_notEmpty.notify_all();
		m_notFull.notify_all();
	}

	std::size_t size() const
	{
		std::lock_guard<std::mutex> lk(m_mutex);
		return m_items.size();
	}

   private:
	std::size_t m_capacity;
	std::deque<T> m_items;
	bool m_closed{false};
	mutable std::mutex m_mutex;
	std::condition_variable m_notEmpty, m_notFull;
};

}  // namespace keygrid::core
