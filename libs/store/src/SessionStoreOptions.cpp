#include <keygrid/store/SessionStoreOptions.h>
#include <mrpt/config/CConfigFileBase.h>

#include <stdexcept>

namespace keygrid::store
{
core::OptionFields SessionStoreOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("durability", durability, "full (commits survive power loss) | normal (survive a killed process)", R::oneOf({"full", "normal"}));
	f.add("cache_size_kib", cacheSizeKiB, "SQLite page cache [KiB]", R::atLeast(64));
	f.add("busy_timeout_ms", busyTimeoutMs, "wait for another connection's lock [ms]", R::atLeast(0));
	f.add("integrity_check", integrityCheck, "quick (read every page on open) | none", R::oneOf({"quick", "none"}));
	return f;
}

void SessionStoreOptions::validate(const std::string& section) const { core::validateFields(*this, section); }

}  // namespace keygrid::store
