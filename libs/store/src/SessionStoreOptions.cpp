#include <keygrid/core/ConfigReading.h>
#include <keygrid/store/SessionStoreOptions.h>
#include <mrpt/config/CConfigFileBase.h>

#include <stdexcept>

namespace keygrid::store
{
bool SessionStoreOptions::isValid(std::string* error) const
{
	const auto bad = [&](const std::string& why) {
		if (error) *error = why;
		return false;
	};
	if (durability != "full" && durability != "normal") return bad("durability must be full or normal, got '" + durability + "'");
	if (cacheSizeKiB < 64) return bad("cache_size_kib must be >= 64, got " + std::to_string(cacheSizeKiB));
	if (busyTimeoutMs < 0) return bad("busy_timeout_ms must be >= 0, got " + std::to_string(busyTimeoutMs));
	if (integrityCheck != "quick" && integrityCheck != "none")
		return bad("integrity_check must be quick or none, got '" + integrityCheck + "'");
	return true;
}

void SessionStoreOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
	durability = cfg.read_string(section, "durability", durability);
	cacheSizeKiB = static_cast<int>(core::readFiniteNumber(cfg, section, "cache_size_kib", cacheSizeKiB));
	busyTimeoutMs = static_cast<int>(core::readFiniteNumber(cfg, section, "busy_timeout_ms", busyTimeoutMs));
	integrityCheck = cfg.read_string(section, "integrity_check", integrityCheck);
	std::string why;
	if (!isValid(&why)) throw std::invalid_argument("[" + section + "] " + why);
}

void SessionStoreOptions::saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const
{
	cfg.write(section, "durability", durability, 30, 40, "full (commits survive power loss) | normal (survive a killed process)");
	cfg.write(section, "cache_size_kib", cacheSizeKiB, 30, 40, "SQLite page cache [KiB]");
	cfg.write(section, "busy_timeout_ms", busyTimeoutMs, 30, 40, "wait for another connection's lock [ms]");
	cfg.write(section, "integrity_check", integrityCheck, 30, 40, "quick (read every page on open) | none");
}

}  // namespace keygrid::store
