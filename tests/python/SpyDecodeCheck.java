// Decodes one LOADID_ESTIMATE message the way lcm-spy does: its
// LCMTypeDatabase scans the class path for LCM types and maps the message's
// fingerprint to a class, which decodes the bytes. Prints the class and
// the fields the test sent; exits 1 when nothing came or nothing matched.
// Usage: java -cp LCM.JAR:TYPES.JAR SpyDecodeCheck.java LCM_URL
import java.io.ByteArrayInputStream;
import java.io.DataInputStream;

import lcm.lcm.LCM;
import lcm.spy.LCMTypeDatabase;

public class SpyDecodeCheck {
    public static void main(String[] args) throws Exception {
        LCMTypeDatabase db = new LCMTypeDatabase();
        LCM lcm = new LCM(args[0]);
        final StringBuilder out = new StringBuilder();
        final Object done = new Object();
        lcm.subscribe("LOADID_ESTIMATE", (l, channel, in) -> {
            try {
                byte[] data = new byte[in.available()];
                in.readFully(data);
                long fp = new DataInputStream(new ByteArrayInputStream(data)).readLong();
                Class<?> c = db.getClassByFingerprint(fp);
                String text;
                if (c == null) {
                    text = String.format("no class for fingerprint %016x", fp);
                } else {
                    Object m = c.getConstructor(byte[].class).newInstance((Object) data);
                    text = c.getName() + " method=" + c.getField("method").get(m) + " state="
                           + c.getField("state").get(m) + " load_name="
                           + c.getField("load_name").get(m) + " mass="
                           + c.getField("mass").get(m);
                }
                synchronized (done) {
                    if (out.length() == 0) out.append(text);
                    done.notifyAll();
                }
            } catch (Exception e) {
                synchronized (done) {
                    if (out.length() == 0) out.append("decode failed: " + e);
                    done.notifyAll();
                }
            }
        });
        synchronized (done) {
            if (out.length() == 0) done.wait(20000);
        }
        System.out.println(out.length() == 0 ? "nothing received" : out.toString());
        System.exit(out.toString().startsWith("loadid.estimate_t ") ? 0 : 1);
    }
}
